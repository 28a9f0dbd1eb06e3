#!/usr/bin/env python3
"""Speed figures side by side (results/bench/bench.csv, written by `raycost bench`).

Left: rays per second against the number of spheres n (log-log), one line per (engine, threads); an
engine measured without a finite n (n = 0, e.g. grid-infinite, the lazily generated infinite scene) is
drawn as a horizontal line. Rows with mismatches > 0 (first hit differs from brute force) are circled
in red. Right: build time against n (log-log), with a slope-1 reference.
Engines without an n (DETP rows such as sphere-cache, incremental) are left out.
"""

import math

import raycost_plot as rp

NAME = "bench"
REQUIRED = ["engine", "n", "threads", "rays_per_s", "build_s"]
STYLES = {"grid": ("o", "-"), "grid-infinite": ("", "--"), "brute-force": ("s", "-"), "embree": ("D", "-")}


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    rows = [r for r in rows if isinstance(r.get("n"), (int, float)) and r["n"] == r["n"]]
    if not rows:
        raise rp.PlotError("%s: no rows with a number of spheres n" % args.input)
    finite_n = [r["n"] for r in rows if r["n"] > 0]
    keys, groups = rp.group_by(rows, "engine", "threads")
    engines = []
    for e, _ in groups:
        if e not in engines:
            engines.append(e)

    fig, axes = rp.subplots(1, 2, panel_w=6.2, panel_h=4.6)
    ax, ax_b = axes[0]
    bad = []
    for (engine, threads), grp in groups.items():
        grp = rp.sort_by(grp, "n")
        color = "C%d" % (engines.index(engine) % 10)
        marker, ls = STYLES.get(engine, ("^", "-"))
        if threads not in (None, 1):
            ls = ":" if ls == "-" else "-."
        label = "%s, %s thread%s" % (engine, threads, "" if threads == 1 else "s")
        if all(r["n"] <= 0 for r in grp):
            # no finite n: a horizontal line across the plot
            y = grp[0]["rays_per_s"]
            ax.axhline(y, color=color, ls=ls, lw=1.4, label=label + " (infinite scene)")
        else:
            grp = [r for r in grp if r["n"] > 0]
            ax.plot(rp.col(grp, "n"), rp.col(grp, "rays_per_s"), marker=marker or "o", ls=ls,
                    color=color, label=label, ms=5)
            if threads in (None, 1) or not any(
                    t in (None, 1) for (e, t) in groups if e == engine):
                builds = [(r["n"], r["build_s"]) for r in grp if r["build_s"] == r["build_s"] and r["build_s"] > 0]
                if builds:
                    ax_b.plot([b[0] for b in builds], [b[1] for b in builds], marker=marker or "o",
                              color=color, label=engine, ms=5)
        bad += [r for r in grp if (r.get("mismatches") or 0) > 0]
    for r in bad:
        ax.plot([r["n"] if r["n"] > 0 else max(finite_n or [1])], [r["rays_per_s"]], "o", ms=14,
                mfc="none", mec="red", mew=1.5)
    rp.log_scale(ax, x=True, y=True)
    ax.set_xlabel("n  (spheres)")
    ax.set_ylabel("rays per second")
    ax.set_title("throughput (higher is better)", fontsize=10)
    ax.legend(fontsize=7.5, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)
    checked = sum((r.get("checked") or 0) for r in rows)
    mism = sum((r.get("mismatches") or 0) for r in rows)
    rp.text_box(ax, "mismatches vs brute force: %d in %d checked rays%s"
                % (mism, checked, "" if mism == 0 else "  ← must be 0"), loc="upper right", fontsize=7.5)
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi * 3)

    pts = [(x, y) for line in ax_b.get_lines() for x, y in zip(*line.get_data())]
    if pts:
        x0, y0 = max(pts)
        lo = min(p[0] for p in pts)
        ax_b.plot([lo, x0], [y0 * lo / x0, y0], ls="--", color="0.5", lw=1, label="slope 1 (∝ n)")
        rp.log_scale(ax_b, x=True, y=True)
        ax_b.legend(fontsize=8, loc="upper left")
    else:
        ax_b.text(0.5, 0.5, "no build times > 0", ha="center", transform=ax_b.transAxes)
    ax_b.set_xlabel("n  (spheres)")
    ax_b.set_ylabel("build time [s]")
    ax_b.set_title("build time", fontsize=10)
    for a in axes[0]:
        a.grid(True, which="major", alpha=0.3)
        if finite_n:
            rp.pad_log_limits(a, finite_n, factor=1.6)
    fig.suptitle("raycost bench: speed figures", fontsize=11, y=1.0)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
