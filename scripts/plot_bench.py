#!/usr/bin/env python3
"""Speed figures of `raycost bench` (results/bench/bench.csv and bench.rounds.csv).

Top left: rays per second against the number of spheres n (log-log), one line per (engine, threads)
-- the picture of the grid's O(1) query against the BVH's O(log n); the lazily generated infinite
scene (n = 0) is a horizontal line. Rows with mismatches > 0 are circled in red.
Top right: how many times faster the grid is than Embree, per n: the median of the per-round paired
ratios (every round traces the same fresh rays with both engines), with their range as error bars.
Bottom left: the grid's time per visited cell and its cells per ray against n: rays/s can only be
flat in n if both are. Bottom right: build time and peak memory against n.

The DETP engines' rows (sphere cache, grid and octree disc indices, brute force on a subset of
points) go to a second figure, NAME.detp.png: wall time and tests per second per engine on 1 and 2
threads, with the 1 → 2 thread speed-up.

The infinite scene's rows (`grid-infinite`, one per cell width and thread count) draw only their best
width in the main figure; all widths go to NAME.infinite.png: rays/s and ns per visited cell against
the cell width, on 1 and 2 threads, beside the finite grid's rays/s (n = 10^6, paired rounds) and
the infinite scene's goal (1/3 of the finite grid's rays/s), with the paired ratio infinite / finite
of each width. A CSV from before the width sweep (one grid-infinite row per thread count) still
plots.
"""

import math

import raycost_plot as rp

NAME = "bench"
REQUIRED = ["engine", "n", "threads", "rays_per_s", "build_s", "peak_mem_bytes", "mismatches"]
STYLES = {"grid": ("o", "-"), "grid-infinite": ("", "--"), "brute-force": ("s", "-"), "embree": ("D", "-")}
DETP = ("sphere-cache", "disc-index-grid", "disc-index-octree")
INFINITE = "grid-infinite"
TARGET_RATIO = 1.0 / 3.0
QUASI_STATIC = ("frame0", "full", "incremental", "kitchen-frame0", "kitchen-full", "kitchen-incremental")


def is_detp(r):
    """A DETP engine's row (brute force on discs carries the DETP rate columns)."""
    rate = r.get("ray_disc_tests_per_s")
    return r["engine"] in DETP or (isinstance(rate, float) and rate == rate)


def plot_detp(rows, args):
    """Wall time and tests per second of each DETP engine on 1 and 2 threads."""
    engines = list(dict.fromkeys(r["engine"] for r in rows))
    threads = sorted({r["threads"] for r in rows})
    fig, axes = rp.subplots(1, 2, panel_w=6.0, panel_h=4.0)
    ax_w, ax_t = axes[0]
    width = 0.8 / len(threads)
    for k, t in enumerate(threads):
        sub = {r["engine"]: r for r in rows if r["threads"] == t}
        xs = [i + (k - (len(threads) - 1) / 2) * width for i in range(len(engines))]
        ax_w.bar(xs, [sub[e]["wall_s"] if e in sub else 0 for e in engines], width,
                 label="%d thread%s" % (t, "" if t == 1 else "s"))
        rate = [max(sub[e].get("ray_sphere_tests_per_s") or 0, sub[e].get("ray_disc_tests_per_s") or 0)
                if e in sub else 0 for e in engines]
        ax_t.bar(xs, rate, width, label="%d thread%s" % (t, "" if t == 1 else "s"))
    for a in (ax_w, ax_t):
        a.set_xticks(range(len(engines)))
        a.set_xticklabels(engines, rotation=15, fontsize=8)
        a.legend(fontsize=8)
    ax_w.set_ylabel("wall time, s (brute force: a subset of points)")
    ax_t.set_yscale("log")
    ax_t.set_ylabel("tests/s (cache: sphere tests)")
    r0 = rows[0]
    mism = sum(int(r["mismatches"]) for r in rows)
    fig.suptitle("DETP engines: %d lines × %d points, %d mismatches against brute force"
                 % (r0["rays"], max(r["n"] for r in rows), mism), fontsize=10)
    args.output = rp.default_png(args.input, "detp")
    rp.finish(fig, args)


def paired_ratios(rounds, n, threads):
    """Per-round grid/Embree speed ratios at (n, threads) from bench.rounds.csv."""
    def secs(engine):
        rs = [r for r in rounds if r["engine"] == engine and r["n"] == n and r["threads"] == threads]
        return {r["round"]: r["round_s"] / r["rays"] for r in rs}

    g, e = secs("grid"), secs("embree")
    return [e[k] / g[k] for k in sorted(g) if k in e]


def median(xs):
    xs = sorted(xs)
    m = len(xs)
    return math.nan if m == 0 else (xs[m // 2] if m % 2 else 0.5 * (xs[m // 2 - 1] + xs[m // 2]))


def plot_quasi_static(rows, args):
    """Seconds of frame 0, one incremental frame and a full recalculation of it, per scene."""
    fig, axes = rp.subplots(1, 1, panel_w=6.5, panel_h=4.0)
    ax = axes[0][0]
    names = [r["engine"] for r in rows]
    secs = [r["frame_s"] for r in rows]
    ax.bar(range(len(rows)), secs, color=["C%d" % (0 if "frame0" in n else 1 if "full" in n else 2) for n in names])
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels(names, rotation=15, fontsize=8)
    ax.set_yscale("log")
    ax.set_ylabel("seconds")
    by = {r["engine"]: r for r in rows}
    lines = []
    for scene, pre in (("Cornell", ""), ("kitchen", "kitchen-")):
        inc, full = by.get(pre + "incremental"), by.get(pre + "full")
        if inc and full:
            lines.append("%s: incremental %.1f× faster than full, frame / implied %.2f, %d mismatches" % (
                scene, full["frame_s"] / inc["frame_s"], inc["frame_s"] / inc["implied_s"], inc["mismatches"]))
    for l in lines:
        print(l)
    rp.text_box(ax, "\n".join(lines), loc="upper right", fontsize=7.5)
    ax.set_title("quasi-static: one frame, incremental vs full", fontsize=10)
    args.output = rp.default_png(args.input, "quasi-static")
    rp.finish(fig, args)


def best_infinite(rows):
    """Per thread count, the infinite scene's best row: the one marked timed_best, else the fastest."""
    best = {}
    for r in rows:
        if r["engine"] != INFINITE:
            continue
        t = r["threads"]
        marked = lambda x: (x.get("timed_best") or 0) == 1
        if t not in best or (marked(r), r["rays_per_s"]) > (marked(best[t]), best[t]["rays_per_s"]):
            best[t] = r
    return best


def plot_infinite(rows, args):
    """The infinite scene at every cell width: rays/s and ns per cell, against the finite grid."""
    fig, axes = rp.subplots(1, 2, panel_w=6.2, panel_h=4.4)
    ax, ax_c = axes[0]
    lines = []
    for k, t in enumerate(sorted({r["threads"] for r in rows})):
        grp = rp.sort_by([r for r in rows if r["threads"] == t], "cell_width")
        label = "%d thread%s" % (t, "" if t == 1 else "s")
        color = "C%d" % k
        ax.plot(rp.col(grp, "cell_width"), rp.col(grp, "rays_per_s"), "o-", color=color, ms=5,
                label="infinite, " + label)
        ax_c.plot(rp.col(grp, "cell_width"), [r["cell_s"] * 1e9 for r in grp], "o-", color=color, ms=5,
                  label=label)
        best = best_infinite(grp)[t]
        ax.plot([best["cell_width"]], [best["rays_per_s"]], "*", color=color, ms=14, mec="k")
        fin = best.get("finite_rays_per_s")
        if isinstance(fin, (int, float)) and fin == fin and fin > 0:
            ax.axhline(fin, color=color, ls="--", lw=1.2,
                       label="finite grid, n = %.0e, %s" % (best["finite_n"], label))
            ax.axhline(fin * TARGET_RATIO, color=color, ls=":", lw=1.0, label="target: finite / 3, " + label)
            for r in grp:
                ratio = r.get("timed_finite_ratio")
                if isinstance(ratio, float) and ratio == ratio:
                    ax.annotate("%.3f" % ratio, (r["cell_width"], r["rays_per_s"]), textcoords="offset points",
                                xytext=(4, 5 - 12 * k), fontsize=7, color=color)
            lines.append("%s: best a = %.2f, %.3g rays/s = %.3f × finite (paired rounds %.3f–%.3f)" % (
                label, best["cell_width"], best["rays_per_s"], best["timed_finite_ratio"],
                best["timed_finite_ratio_min"], best["timed_finite_ratio_max"]))
        else:
            lines.append("%s: best a = %.2f, %.3g rays/s" % (label, best["cell_width"], best["rays_per_s"]))
    for l in lines:
        print(l)
    rp.log_scale(ax, x=True, y=True)
    ax.set_xlabel("cell width a")
    ax.set_ylabel("rays per second (median over rounds)")
    ax.set_title("infinite Poisson scene (ρ = 1, r = 0.1; ★ best width; labels: infinite / finite)",
                 fontsize=9)
    ax.legend(fontsize=7, loc="center right")
    rp.log_scale(ax_c, x=True)
    ax_c.set_ylim(bottom=0)
    ax_c.set_xlabel("cell width a")
    ax_c.set_ylabel("ns per visited cell (median round)")
    ax_c.set_title("cost per visited cell (N_S + 1 per ray)", fontsize=10)
    ax_c.legend(fontsize=7.5)
    for a in (ax, ax_c):
        a.grid(True, which="major", alpha=0.3)
    fig.suptitle("raycost bench, infinite scene: " + "; ".join(lines), fontsize=8.5)
    args.output = rp.default_png(args.input, "infinite")
    rp.finish(fig, args)


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    qs_rows = [r for r in rows if r["engine"] in QUASI_STATIC]
    rows = [r for r in rows if r["engine"] not in QUASI_STATIC]
    detp_rows = [r for r in rows if is_detp(r)]
    rows = [r for r in rows if not is_detp(r)]
    rows = [r for r in rows if isinstance(r.get("n"), (int, float)) and r["n"] == r["n"]]
    inf_rows = [r for r in rows if r["engine"] == INFINITE]
    # The main figure shows the infinite scene at its best width only.
    best = {id(r) for r in best_infinite(inf_rows).values()}
    rows = [r for r in rows if r["engine"] != INFINITE or id(r) in best]
    if not rows:
        raise rp.PlotError("%s: no rows with a number of spheres n" % args.input)
    finite_n = sorted({r["n"] for r in rows if r["n"] > 0})
    _, groups = rp.group_by(rows, "engine", "threads")
    engines = []
    for e, _ in groups:
        if e not in engines:
            engines.append(e)
    color_of = {e: "C%d" % (i % 10) for i, e in enumerate(engines)}

    fig, axes = rp.subplots(2, 2, panel_w=6.2, panel_h=4.4)
    ax, ax_r = axes[0]
    ax_c, ax_b = axes[1]

    # Throughput.
    bad = []
    for (engine, threads), grp in groups.items():
        marker, ls = STYLES.get(engine, ("^", "-"))
        if threads not in (None, 1):
            ls = ":" if ls == "-" else "-."
        label = "%s, %s thread%s" % (engine, threads, "" if threads == 1 else "s")
        if all(r["n"] <= 0 for r in grp):
            width = grp[0].get("cell_width")
            ax.axhline(grp[0]["rays_per_s"], color=color_of[engine], ls=ls, lw=1.4,
                       label=label + " (infinite scene%s)" % (
                           ", best a = %.2f" % width if engine == INFINITE and len(inf_rows) > 2 else ""))
        else:
            grp = rp.sort_by([r for r in grp if r["n"] > 0], "n")
            ax.plot(rp.col(grp, "n"), rp.col(grp, "rays_per_s"), marker=marker or "o", ls=ls,
                    color=color_of[engine], label=label, ms=5)
        bad += [r for r in grp if (r.get("mismatches") or 0) > 0]
    for r in bad:
        ax.plot([r["n"] if r["n"] > 0 else max(finite_n or [1])], [r["rays_per_s"]], "o", ms=14,
                mfc="none", mec="red", mew=1.5)
    rp.log_scale(ax, x=True, y=True)
    ax.set_xlabel("n  (spheres)")
    ax.set_ylabel("rays per second (median over rounds)")
    ax.set_title("throughput (higher is better)", fontsize=10)
    ax.legend(fontsize=7, loc="lower left", ncol=2)
    checked = sum((r.get("checked") or 0) for r in rows)
    mism = sum((r.get("mismatches") or 0) for r in rows)
    rp.text_box(ax, "mismatches: %d in %d checked answers%s"
                % (mism, checked, "" if mism == 0 else "  <- must be 0"), loc="upper right", fontsize=7.5)

    # Paired ratios grid / Embree.
    try:
        rounds = rp.read_csv(rp.sibling_csv(args.input, "rounds"),
                             ["engine", "n", "threads", "round", "rays", "round_s"])
    except rp.PlotError:
        rounds = []
    drawn = False
    for k, threads in enumerate(sorted({r["threads"] for r in rounds if r["engine"] == "embree"})):
        pts = []
        for n in finite_n:
            ratios = paired_ratios(rounds, n, threads)
            if ratios:
                pts.append((n, median(ratios), min(ratios), max(ratios)))
        if not pts:
            continue
        xs = [p[0] * (1.0 + 0.06 * k) for p in pts]
        ys = [p[1] for p in pts]
        ax_r.errorbar(xs, ys, yerr=[[p[1] - p[2] for p in pts], [p[3] - p[1] for p in pts]],
                      fmt="o-", capsize=3, ms=5,
                      label="grid / Embree, %d thread%s" % (threads, "" if threads == 1 else "s"))
        for x, y in zip(xs, ys):
            ax_r.annotate("%.2f" % y, (x, y), textcoords="offset points", xytext=(6, 4), fontsize=7)
        drawn = True
    if drawn:
        ax_r.axhline(1.0, color="0.5", lw=0.8)
        rp.log_scale(ax_r, x=True)
        ax_r.set_ylim(bottom=0)
        ax_r.legend(fontsize=7.5, loc="upper left")
    else:
        ax_r.text(0.5, 0.5, "no Embree rows (build with --features embree)", ha="center",
                  transform=ax_r.transAxes, fontsize=8)
    ax_r.set_xlabel("n  (spheres)")
    ax_r.set_ylabel("speed ratio (median of paired rounds, range)")
    ax_r.set_title("how many times faster the grid is", fontsize=10)

    # Cost per cell and cells per ray.
    grid_rows = [r for r in rows if r["engine"] == "grid" and r["n"] > 0 and rp.has([r], "cell_s")]
    if grid_rows:
        ax_s = ax_c.twinx()
        for threads in sorted({r["threads"] for r in grid_rows}):
            grp = rp.sort_by([r for r in grid_rows if r["threads"] == threads], "n")
            ax_c.plot(rp.col(grp, "n"), [r["cell_s"] * 1e9 for r in grp], "o-", ms=5,
                      label="ns per cell, %d thread%s" % (threads, "" if threads == 1 else "s"))
        grp = rp.sort_by([r for r in grid_rows if r["threads"] == grid_rows[0]["threads"]], "n")
        ax_s.plot(rp.col(grp, "n"), [r["n_s_mean"] + 1 for r in grp], "s--", color="0.4", ms=4,
                  label="cells per ray (N_S + 1)")
        ax_s.set_ylabel("cells per ray")
        ax_s.set_ylim(bottom=0)
        rp.log_scale(ax_c, x=True)
        ax_c.set_ylim(bottom=0)
        h1, l1 = ax_c.get_legend_handles_labels()
        h2, l2 = ax_s.get_legend_handles_labels()
        ax_c.legend(h1 + h2, l1 + l2, fontsize=7.5, loc="lower right")
    ax_c.set_xlabel("n  (spheres)")
    ax_c.set_ylabel("grid: ns per visited cell (median round)")
    ax_c.set_title("grid cost per unit of work", fontsize=10)

    # Build time and peak memory.
    ax_m = ax_b.twinx()
    for engine in ("grid", "embree"):
        grp = rp.sort_by([r for r in rows if r["engine"] == engine and r["n"] > 0 and r["build_s"] > 0
                          and r["threads"] == min(x["threads"] for x in rows if x["engine"] == engine)], "n")
        if not grp:
            continue
        ax_b.plot(rp.col(grp, "n"), rp.col(grp, "build_s"), "o-", color=color_of[engine], ms=5,
                  label="%s build" % engine)
        # Below a megabyte the resident-set readings are page-granular noise.
        mem = [r for r in grp if r["peak_mem_bytes"] >= 1e6]
        ax_m.plot(rp.col(mem, "n"), [r["peak_mem_bytes"] / 1e9 for r in mem], "^:",
                  color=color_of[engine], ms=5, label="%s peak memory" % engine)
    rp.log_scale(ax_b, x=True, y=True)
    rp.log_scale(ax_m, y=True)
    ax_b.set_xlabel("n  (spheres)")
    ax_b.set_ylabel("build time [s]")
    ax_m.set_ylabel("peak memory, scene included [GB]")
    ax_b.set_title("build time and memory", fontsize=10)
    h1, l1 = ax_b.get_legend_handles_labels()
    h2, l2 = ax_m.get_legend_handles_labels()
    ax_b.legend(h1 + h2, l1 + l2, fontsize=7.5, loc="upper left")

    for a in (ax, ax_r, ax_c, ax_b):
        a.grid(True, which="major", alpha=0.3)
        if finite_n:
            rp.pad_log_limits(a, finite_n, factor=1.6)
    fig.suptitle("raycost bench: the grid and Embree on the same spheres and rays", fontsize=11, y=1.0)
    rp.finish(fig, args)
    if detp_rows:
        plot_detp(detp_rows, args)
    if qs_rows:
        plot_quasi_static(qs_rows, args)
    if len({r.get("cell_width") for r in inf_rows}) > 1:
        plot_infinite(inf_rows, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
