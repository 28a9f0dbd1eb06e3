#!/usr/bin/env python3
"""Theorem 2: dynamic points by the sphere cache vs by a disc index as r_D/r_0 grows (experiment
quasi-static-crossover). One column per feed (dynamic.feed: "paper" = Theorem 2's model, the sphere
cache gets the segment index's answer and the disc index every segment; "segment-index" = both get
that answer; "all" = both get every segment). Top: seconds per frame for the dynamic points, each
engine (mean ± 95 % CI across replicas). Bottom: counted cost per frame (ray–sphere + ray–disc tests
+ the disc index's box tests and DDA steps, weight 1 each) with Theorem 2's costs for the same n_R
and n_D (t = u), whose crossover is 1/√8.08 ≈ 0.35 at n → ∞. The measured crossovers carry a 95 %
parametric-bootstrap CI over the replicas.
"""
import raycost_plot as rp
from raycost_stats import bootstrap, crossing, dof

NAME = "quasi-static-crossover"
REQUIRED = ["dynamic.ratio", "detp.engine", "dynamic_s_mean", "dynamic_s_se", "dynamic_counted_cost_mean",
            "dynamic_counted_cost_se", "dynamic_tests_theory_sphere_cache", "dynamic_tests_theory_disc_index",
            "crossover_theory"]


def cross_ci(sc, di, metric):
    xs = rp.col(sc, "dynamic.ratio")
    k = len(sc)
    means = rp.col(sc, metric + "_mean") + rp.col(di, metric + "_mean")
    ses = rp.col(sc, metric + "_se") + rp.col(di, metric + "_se")
    dofs = [dof(r, metric) for r in sc + di]
    return bootstrap(lambda v: crossing(xs, v[:k], v[k:]), means, ses, dofs=dofs)


def text(c):
    x, lo, hi = c
    return "none in range" if x != x else "%.3f [%.3f, %.3f]" % (x, lo, hi)


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    feeds = sorted({r["dynamic.feed"] for r in rows}) if rp.has(rows, "dynamic.feed") else [None]
    fig, axes = rp.subplots(2, len(feeds), panel_w=5.0, panel_h=4.0)
    for c, feed in enumerate(feeds):
        sub = [r for r in rows if feed is None or r["dynamic.feed"] == feed]
        sc = rp.sort_by([r for r in sub if r["detp.engine"] == "sphere-cache"], "dynamic.ratio")
        di = rp.sort_by([r for r in sub if r["detp.engine"] == "disc-index"], "dynamic.ratio")
        ax_t, ax_c = axes[0][c], axes[1][c]
        x = rp.col(sc, "dynamic.ratio")
        for ax, metric, what in ((ax_t, "dynamic_s", "seconds"), (ax_c, "dynamic_counted_cost", "counted")):
            for grp, color, marker, label in ((sc, "C0", "o", "sphere cache"), (di, "C1", "s", "disc index")):
                # Each replica one cluster: Student-t on M_clusters − 1 degrees of freedom.
                ax.errorbar(x, rp.col(grp, metric + "_mean"), yerr=[rp.ci95(r, metric) for r in grp],
                            fmt=marker, color=color, ms=4, capsize=2, label=label)
            cr = cross_ci(sc, di, metric)
            if cr[0] == cr[0]:
                ax.axvline(cr[0], color="C3", ls="--", lw=1, label="crossover %s" % text(cr))
            ax.axvline(0.35, color="0.4", ls=":", lw=1, label="Theorem 2: 0.35")
            print("feed %s: crossover r_D/r_0 by %s: %s" % (feed, what, text(cr)))
            rp.log_scale(ax, x=True, y=True)
            ax.set_xlabel("r_D / r_0")
        ax_c.plot(x, rp.col(sc, "dynamic_tests_theory_sphere_cache"), "-", color="C0", lw=0.9, label="8.08·n_R·(r_D/r_0)²·∛n_D")
        ax_c.plot(x, rp.col(sc, "dynamic_tests_theory_disc_index"), "-", color="C1", lw=0.9, label="n_R·∛n_D")
        ax_t.set_title("feed: %s" % (feed or "as run"), fontsize=10)
        ax_t.set_ylabel("seconds per frame, dynamic points")
        ax_c.set_ylabel("counted cost per frame")
        ax_t.legend(fontsize=6)
        ax_c.legend(fontsize=6)
        for a, b in zip(sc, di):
            print("  feed %s, r_D/r_0 %.2f: sphere cache %.4f ± %.4f s, %.3g counted; disc index %.4f ± %.4f s, %.3g counted; n_D %d" % (
                feed, a["dynamic.ratio"], a["dynamic_s_mean"], a["dynamic_s_se"], a["dynamic_counted_cost_mean"],
                b["dynamic_s_mean"], b["dynamic_s_se"], b["dynamic_counted_cost_mean"], a["points_dynamic"]))
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
