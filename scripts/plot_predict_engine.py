#!/usr/bin/env python3
"""The §4.1 predictors (experiment predict-engine): each dynamic-point engine's cost predicted from a
fraction of the photons (one line per dynamic.predictor: "subsample", "paper") against its cost
measured on all of them, over r_D/r_0; the pick of each prediction and of Theorem 2's ratio rule,
and whether each chose the faster engine.
"""

import raycost_plot as rp

NAME = "predict-engine"
REQUIRED = ["dynamic.ratio", "predicted_sphere_cache_s", "predicted_disc_index_s", "measured_sphere_cache_s",
            "measured_disc_index_s", "timed_pick_right", "timed_rule_pick_right", "timed_pick", "timed_best_engine"]


def plot(args):
    rows = rp.sort_by(rp.read_csv(args.input, REQUIRED), "dynamic.ratio")
    # One line per predictor (dynamic.predictor; tables from before it existed are the subsample's).
    keys, groups = rp.group_by(rows, "dynamic.predictor")
    fig, axes = rp.subplots(1, 2, panel_w=5.8, panel_h=4.3)
    ax, ax_e = axes[0]
    styles = ("x--", "+:", "d-.")
    summary = []
    for g, (key, grp) in enumerate(groups.items()):
        name = key[0] if key else "subsample"
        x = rp.col(grp, "dynamic.ratio")
        for eng, c in (("sphere_cache", "C0"), ("disc_index", "C1")):
            label = eng.replace("_", " ")
            if g == 0:
                ax.plot(x, rp.col(grp, "measured_%s_s" % eng), "o-", color=c, label="%s, measured (all photons)" % label)
            ax.plot(x, rp.col(grp, "predicted_%s_s" % eng), styles[g % len(styles)], color=c,
                    label="%s, predicted (%s)" % (label, name))
            ax_e.plot(x, [100 * (p / m - 1) for p, m in zip(rp.col(grp, "predicted_%s_s" % eng), rp.col(grp, "measured_%s_s" % eng))],
                      styles[g % len(styles)], color=c, label="%s, %s" % (label, name))
        right = sum(r["timed_pick_right"] for r in grp)
        rule = sum(r["timed_rule_pick_right"] for r in grp)
        summary.append("%s: pick right %d/%d, Theorem 2 rule %d/%d" % (name, right, len(grp), rule, len(grp)))
        for r in grp:
            print("%s, r_D/r_0 %.2f: predicted SC %.4f s DI %.4f s; measured SC %.4f s DI %.4f s; pick %s, best %s (%s); rule right: %s" % (
                name, r["dynamic.ratio"], r["predicted_sphere_cache_s"], r["predicted_disc_index_s"], r["measured_sphere_cache_s"],
                r["measured_disc_index_s"], r["timed_pick"], r["timed_best_engine"], "right" if r["timed_pick_right"] else "WRONG",
                "yes" if r["timed_rule_pick_right"] else "no"))
    rp.log_scale(ax, x=True, y=True)
    ax.set_xlabel("r_D / r_0")
    ax.set_ylabel("seconds, dynamic points at frame 0")
    ax.legend(fontsize=7)
    ax_e.axhline(0, color="black", lw=0.8)
    ax_e.set_xscale("log")
    ax_e.set_xlabel("r_D / r_0")
    ax_e.set_ylabel("prediction error, %")
    ax_e.legend(fontsize=7)
    rp.text_box(ax_e, "\n".join(summary))
    for line in summary:
        print(line)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
