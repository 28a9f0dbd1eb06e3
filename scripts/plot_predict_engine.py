#!/usr/bin/env python3
"""The §4.1 predictor (experiment predict-engine): each dynamic-point engine's cost predicted from a
fraction of the photons against its cost measured on all of them, over r_D/r_0; the pick of the
prediction and of Theorem 2's ratio rule, and whether each chose the faster engine.
"""

import raycost_plot as rp

NAME = "predict-engine"
REQUIRED = ["dynamic.ratio", "predicted_sphere_cache_s", "predicted_disc_index_s", "measured_sphere_cache_s",
            "measured_disc_index_s", "timed_pick_right", "timed_rule_pick_right", "timed_pick", "timed_best_engine"]


def plot(args):
    rows = rp.sort_by(rp.read_csv(args.input, REQUIRED), "dynamic.ratio")
    fig, axes = rp.subplots(1, 2, panel_w=5.8, panel_h=4.3)
    ax, ax_e = axes[0]
    x = rp.col(rows, "dynamic.ratio")
    for eng, c in (("sphere_cache", "C0"), ("disc_index", "C1")):
        ax.plot(x, rp.col(rows, "measured_%s_s" % eng), "o-", color=c, label="%s, measured (all photons)" % eng.replace("_", " "))
        ax.plot(x, rp.col(rows, "predicted_%s_s" % eng), "x--", color=c, label="%s, predicted (fraction)" % eng.replace("_", " "))
        ax_e.plot(x, [100 * (p / m - 1) for p, m in zip(rp.col(rows, "predicted_%s_s" % eng), rp.col(rows, "measured_%s_s" % eng))],
                  "o-", color=c, label=eng.replace("_", " "))
    rp.log_scale(ax, x=True, y=True)
    ax.set_xlabel("r_D / r_0")
    ax.set_ylabel("seconds, dynamic points at frame 0")
    ax.legend(fontsize=7)
    ax_e.axhline(0, color="black", lw=0.8)
    ax_e.set_xscale("log")
    ax_e.set_xlabel("r_D / r_0")
    ax_e.set_ylabel("prediction error, %")
    ax_e.legend(fontsize=7)
    right = sum(r["timed_pick_right"] for r in rows)
    rule = sum(r["timed_rule_pick_right"] for r in rows)
    rp.text_box(ax_e, "pick right: predictor %d/%d, Theorem 2 rule %d/%d" % (right, len(rows), rule, len(rows)))
    for r in rows:
        print("r_D/r_0 %.2f: predicted SC %.4f s DI %.4f s; measured SC %.4f s DI %.4f s; pick %s, best %s (%s); rule right: %s" % (
            r["dynamic.ratio"], r["predicted_sphere_cache_s"], r["predicted_disc_index_s"], r["measured_sphere_cache_s"],
            r["measured_disc_index_s"], r["timed_pick"], r["timed_best_engine"], "right" if r["timed_pick_right"] else "WRONG",
            "yes" if r["timed_rule_pick_right"] else "no"))
    print("predictor right %d/%d, Theorem 2 rule right %d/%d" % (right, len(rows), rule, len(rows)))
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
