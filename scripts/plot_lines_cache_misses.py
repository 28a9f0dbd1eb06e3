#!/usr/bin/env python3
"""Sphere-cache misses per level: Lebesgue (Morton) vs Hilbert order (the paper's Figures 9 and 10).

One column per Q. Top: misses (re-builds of a level after the cache's first chain) per level for
each order, log y; with --unsorted (default: results/lines-cache-misses-unsorted/...csv if present)
the unsorted baseline too, scaled to the sorted runs' point count. Bottom: Hilbert's misses over
Morton's per level (below 1: Hilbert's peaks are lower). Grey verticals mark the levels whose radius
is closest to 2^(−k) of the root's (the paper's local maxima).
"""

import math
import os

import raycost_plot as rp

NAME = "lines-cache-misses"
REQUIRED = ["level", "misses_level", "radius"]


def extra(p):
    p.add_argument("--unsorted", default=os.path.join("results", NAME + "-unsorted", NAME + "-unsorted.csv"),
                   help="the unsorted baseline's CSV (default: %(default)s; skipped if missing)")


def plot(args):
    main, levels = rp.with_params(args.input, "levels", REQUIRED)
    points = max(r["points"] for r in main)
    base = []
    if args.unsorted and os.path.exists(args.unsorted):
        umain, base = rp.with_params(args.unsorted, "levels", REQUIRED)
        scale = points / max(r["points"] for r in umain)
        for r in base:
            r["detp.order"] = "none (×%g)" % scale
            r["misses_level"] = r["misses_level"] * scale
    qs = sorted({r["detp.q"] for r in levels})
    fig, axes = rp.subplots(2, len(qs), panel_w=6.0, panel_h=3.8)
    for ax, ax_r, q in zip(axes[0], axes[1], qs):
        rows = [r for r in levels + base if r.get("detp.q") == q]
        keys, groups = rp.group_by(rows, "detp.order")
        for j, (value, grp) in enumerate(groups.items()):
            grp = rp.sort_by(grp, "level")
            ax.plot(rp.col(grp, "level"), rp.col(grp, "misses_level"), "o-", ms=3, lw=1,
                    color="C%d" % j, label=str(value[0]))
        by = {o[0]: {r["level"]: r["misses_level"] for r in g} for o, g in groups.items()}
        if "hilbert" in by and "morton" in by:
            lv = sorted(k for k in by["hilbert"] if by["morton"].get(k))
            ratio = [by["hilbert"][k] / by["morton"][k] for k in lv]
            ax_r.plot(lv, ratio, "o-", ms=3, lw=1, color="C2")
            ax_r.axhline(1, color="black", lw=0.8)
            print("Q = %g: Hilbert/Morton misses per level: %s" % (q, " ".join("%d:%.2f" % x for x in zip(lv, ratio))))
        deepest = max(r["level"] for r in rows)
        k = 1
        while True:
            lvl = k * math.log(2) / -math.log(q)
            if lvl > deepest:
                break
            for a in (ax, ax_r):
                a.axvline(round(lvl), color="0.75", lw=0.8, ls=":")
            k += 1
        ax.set_yscale("log")
        ax.set_title("Q = %g, %d points, %d lines" % (q, points, main[0]["segments"]), fontsize=10)
        ax.set_ylabel("cache misses (re-builds)")
        ax.legend(fontsize=8)
        ax_r.set_xlabel("level i (grey: radius ≈ 2^(−k) of the root)")
        ax_r.set_ylabel("Hilbert / Morton misses")
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME, extra=extra)
