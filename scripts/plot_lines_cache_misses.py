#!/usr/bin/env python3
"""Sphere-cache misses per level: Lebesgue (Morton) vs Hilbert order (the paper's Figures 9 and 10),
read both ways. One column per Q. Top: misses per level and replica (mean ± 95 % CI across replicas;
a miss at level i rebuilds level i and every level below it, so this count is cumulative), for each
order and point count, log y; with --unsorted (default: results/lines-cache-misses-unsorted/...csv if
present) the unsorted baseline too, scaled to the largest sorted point count. Middle: misses that
*start* at each level (the first difference of the top row: points whose chain first breaks there).
Bottom: Hilbert / Morton for both readings at the largest point count. Grey verticals mark the levels
whose radius is closest to 2^(−k) of the root's (the paper's local maxima).
"""
import math
import os

import raycost_plot as rp
from raycost_stats import t95

NAME = "lines-cache-misses"
REQUIRED = ["level", "misses_level_per_replica_mean", "misses_level_per_replica_se",
            "misses_level_per_replica_n", "radius"]


def extra(p):
    p.add_argument("--unsorted", default=os.path.join("results", NAME + "-unsorted", NAME + "-unsorted.csv"),
                   help="the unsorted baseline's CSV (default: %(default)s; skipped if missing)")


def starts(values):
    """Misses that start at each level: the first difference of the cumulative count."""
    return [b - a for a, b in zip([0.0] + values, values)]


def plot(args):
    main, levels = rp.with_params(args.input, "levels", REQUIRED)
    points_of = {r["point"]: r["points"] for r in main}
    for r in levels:
        r["n_points"] = points_of[r["point"]]
    top = max(points_of.values())
    base = []
    if args.unsorted and os.path.exists(args.unsorted):
        umain, base = rp.with_params(args.unsorted, "levels", REQUIRED)
        upoints = {r["point"]: r["points"] for r in umain}
        for r in base:
            scale = top / upoints[r["point"]]
            r["detp.order"] = "none (×%g)" % scale
            r["n_points"] = top
            r["misses_level_per_replica_mean"] *= scale
            r["misses_level_per_replica_se"] *= scale
    qs = sorted({r["detp.q"] for r in levels})
    fig, axes = rp.subplots(3, len(qs), panel_w=6.0, panel_h=3.3)
    for c, q in enumerate(qs):
        ax, ax_s, ax_r = axes[0][c], axes[1][c], axes[2][c]
        rows = [r for r in levels + base if r.get("detp.q") == q]
        _, groups = rp.group_by(rows, "detp.order", "n_points")
        series = {}
        for j, (value, grp) in enumerate(sorted(groups.items(), key=lambda kv: (str(kv[0][0]), kv[0][1]))):
            grp = rp.sort_by(grp, "level")
            lv = rp.col(grp, "level")
            m = rp.col(grp, "misses_level_per_replica_mean")
            se = rp.col(grp, "misses_level_per_replica_se")
            z = t95(grp[0]["misses_level_per_replica_n"] - 1)
            label = "%s, %s points" % (value[0], rp.group_label(("n",), (value[1],)).split("=")[-1])
            style = "o-" if value[1] == top else "s--"
            color = {"morton": "C0", "hilbert": "C1"}.get(value[0], "0.5")
            ax.errorbar(lv, m, yerr=[z * s for s in se], fmt=style, ms=3, lw=1, capsize=1.5, color=color,
                        label=label, alpha=1.0 if value[1] == top else 0.6)
            ax_s.plot(lv, [max(x, 1e-1) for x in starts(m)], style, ms=3, lw=1, color=color, label=label,
                      alpha=1.0 if value[1] == top else 0.6)
            series[value] = dict(zip(lv, m))
        h, mo = series.get(("hilbert", top)), series.get(("morton", top))
        if h and mo:
            lv = sorted(k for k in h if mo.get(k))
            ax_r.plot(lv, [h[k] / mo[k] for k in lv], "o-", ms=3, lw=1, color="C2", label="misses per level")
            sh, sm = starts([h[k] for k in lv]), starts([mo[k] for k in lv])
            lv2 = [k for k, a, b in zip(lv, sh, sm) if b > 0]
            ax_r.plot(lv2, [a / b for a, b in zip(sh, sm) if b > 0], "s-", ms=3, lw=1, color="C4",
                      label="misses starting at the level")
            ax_r.axhline(1, color="black", lw=0.8)
            ax_r.legend(fontsize=7)
            print("Q = %g, %d points: Hilbert/Morton misses per level: %s" % (
                q, top, " ".join("%d:%.3f" % (k, h[k] / mo[k]) for k in lv)))
            print("Q = %g, %d points: Hilbert/Morton misses starting per level: %s" % (
                q, top, " ".join("%d:%.3f" % (k, a / b) for k, a, b in zip(lv, sh, sm) if b > 0)))
        deepest = max(r["level"] for r in rows)
        k = 1
        while True:
            lvl = k * math.log(2) / -math.log(q)
            if lvl > deepest:
                break
            for a in (ax, ax_s, ax_r):
                a.axvline(round(lvl), color="0.75", lw=0.8, ls=":")
            k += 1
        for a in (ax, ax_s):
            a.set_yscale("log")
            a.legend(fontsize=6)
        ax.set_title("Q = %g, %d lines, %d replicas" % (q, main[0]["segments"] / max(1, levels[0]["misses_level_per_replica_n"]),
                                                      levels[0]["misses_level_per_replica_n"]), fontsize=10)
        ax.set_ylabel("misses per level (cumulative)")
        ax_s.set_ylabel("misses starting at the level")
        ax_r.set_xlabel("level i (grey: radius ≈ 2^(−k) of the root)")
        ax_r.set_ylabel("Hilbert / Morton")
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME, extra=extra)
