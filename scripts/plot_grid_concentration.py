#!/usr/bin/env python3
"""Proposition 4.1, measured (experiment grid-concentration).

Since E[N_I] = O(1), P(N_I ≥ c·H(n)) → 0 as n → ∞ for H(n) = ln n and H(n) = √n and any c > 0.
x = scene.spheres (log). Left: p_log = P(N_I ≥ c·ln n); middle: p_sqrt = P(N_I ≥ c·√n); both as mean
± 95 % CI on a log y axis, one line per scaling.c; a probability measured as exactly 0 is drawn as a
downward triangle at the axis floor (below 1/rays). Right: the thresholds c·H(n) (h_log, h_sqrt)
against the measured mean E[N_I] — the probabilities can only fall once the threshold passes the mean.
"""


import raycost_plot as rp

NAME = "grid-concentration"
REQUIRED = ["p_log_mean", "p_log_se", "p_sqrt_mean", "p_sqrt_se"]


def draw_p(ax, groups, keys, n, metric, floor):
    for j, (value, grp) in enumerate(groups.items()):
        grp = rp.sort_by(grp, n)
        color = "C%d" % j
        label = rp.group_label(keys, value) if keys else metric
        pos = [r for r in grp if r[metric + "_mean"] > 0]
        zero = [r for r in grp if r[metric + "_mean"] == 0]
        ax.plot(rp.col(grp, n), [max(v, floor) for v in rp.col(grp, metric + "_mean")], "-",
                color=color, lw=1, alpha=0.6)
        if pos:
            rp.measured(ax, pos, n, metric, color=color, label=label)
        if zero:
            ax.plot(rp.col(zero, n), [floor] * len(zero), "v", color=color, ms=7,
                    label="%s: measured 0" % label if not pos else None)
    rp.log_scale(ax, x=True, y=True)
    ax.set_ylim(floor / 1.5, 1.6)


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    n = next((c for c in ("scene.spheres", "spheres") if rp.has(rows, c)), None)
    if n is None:
        raise rp.PlotError("%s: missing required column scene.spheres (or spheres)" % args.input)
    keys, groups = rp.group_by(rows, "scaling.c")
    rays = max([r.get("p_log_n") or 0 for r in rows] + [1])
    floor = 0.3 / rays

    fig, axes = rp.subplots(1, 3, panel_w=5.0, panel_h=4.2)
    ax_l, ax_s, ax_h = axes[0]
    draw_p(ax_l, groups, keys, n, "p_log", floor)
    ax_l.set_ylabel("probability")
    ax_l.set_title("p_log = P(N_I ≥ c·ln n)", fontsize=10)
    draw_p(ax_s, groups, keys, n, "p_sqrt", floor)
    ax_s.set_title("p_sqrt = P(N_I ≥ c·√n)", fontsize=10)
    for ax in (ax_l, ax_s):
        ax.axhline(1.0 / rays, color="0.6", lw=0.8, ls=":")
        ax.text(0.99, 1.0 / rays, " 1 / rays", transform=ax.get_yaxis_transform(), ha="right",
                va="bottom", fontsize=7, color="0.4")
        ax.legend(fontsize=7.5, loc="best")

    for j, (value, grp) in enumerate(groups.items()):
        grp = rp.sort_by(grp, n)
        label = rp.group_label(keys, value) if keys else ""
        if rp.has(grp, "h_log"):
            ax_h.plot(rp.col(grp, n), rp.col(grp, "h_log"), "-", color="C%d" % j,
                      label="c·ln n, %s" % label)
        if rp.has(grp, "h_sqrt"):
            ax_h.plot(rp.col(grp, n), rp.col(grp, "h_sqrt"), "--", color="C%d" % j,
                      label="c·√n, %s" % label)
    first = rp.sort_by(next(iter(groups.values())), n)
    for metric, color, marker in (("n_i", "black", "o"), ("n_i_mb", "0.45", "s")):
        if rp.has(first, metric + "_mean"):
            rp.measured(ax_h, first, n, metric, color=color, marker=marker,
                        label="E[%s] measured" % metric)
    rp.log_scale(ax_h, x=True, y=True)
    ax_h.set_ylabel("tests per ray")
    ax_h.set_title("thresholds c·H(n) vs measured E[N_I]", fontsize=10)
    ax_h.legend(fontsize=6.5, loc="upper left", ncol=2)
    lo, hi = ax_h.get_ylim()
    ax_h.set_ylim(lo, hi * 10)

    for ax in axes[0]:
        ax.grid(True, which="major", alpha=0.3)
        ax.set_xlabel("n  (scene.spheres)")
        rp.pad_log_limits(ax, rp.col(rows, n), factor=1.5)
    fig.suptitle("%s: Proposition 4.1 — P(N_I ≥ c·H(n)) → 0 as n grows" % NAME, fontsize=11, y=1.0)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
