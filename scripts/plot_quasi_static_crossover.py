#!/usr/bin/env python3
"""Theorem 2: dynamic points by the sphere cache vs by a disc index as r_D/r_0 grows (experiment
quasi-static-crossover). One column per feed (dynamic.feed: "paper" = Theorem 2's model, the sphere
cache gets the segment index's answer and the disc index every segment; "segment-index" = both get
that answer; "all" = both get every segment). Rows, the paper's accounting first:
  1. the paper's: ray–disc + ray–sphere tests per frame (t = u, the index's traversal at weight 0),
     with Theorem 2's costs for the same n_R and n_D (crossover 1/√8.08 ≈ 0.35 at n → ∞);
  2. every counted operation at weight 1 (the index's box tests and DDA steps included);
  3. seconds per frame.
Means ± 95 % CI across replicas. The crossover in each is the registered statistic of
claims/preregistered.toml (rule theorem-2): the root of a weighted polynomial fit of
log(sphere cache / disc index) over the whole range, its interval from a cluster bootstrap over
separate runs and replicas (NAME.frames.csv, frames ≥ 1), widened by the fit's misfit; the shares of
draws with no or several crossings are printed, never dropped.
"""
import os
import tomllib

import raycost_plot as rp
import raycost_stats as S
from claims_data import Tables, per_replica

NAME = "quasi-static-crossover"
REQUIRED = ["dynamic.ratio", "detp.engine", "dynamic_s_mean", "dynamic_s_se", "dynamic_counted_cost_mean",
            "dynamic_counted_cost_se", "dynamic_tests_theory_sphere_cache", "dynamic_tests_theory_disc_index",
            "crossover_theory"]
PREREG = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "claims", "preregistered.toml")
ROWS = (("paper", "the paper's accounting: tests per frame"),
        ("traversal-weight-1", "counted, traversal at weight 1"),
        ("seconds", "seconds per frame"))


def registered():
    with open(PREREG, "rb") as f:
        pre = tomllib.load(f)
    return pre["defaults"], pre["accounting"]


def crossing(tables, sc, di, terms, defaults):
    xs = rp.col(sc, "dynamic.ratio")
    cl = S.Clustered(per_replica(tables, NAME, [r["point"] for r in sc + di], terms))
    c = S.crossover(xs, cl, S.paired_log_ratio(len(xs), cl), defaults["fit_degrees"], defaults["fit_alpha"],
                    defaults["draws"], defaults["seed"], defaults["level"])
    means = cl.observed()[0]
    return c, means[:len(xs)], means[len(xs):]


def text(c):
    iv = c.interval
    shares = ", ".join("%s %.1f %%" % (k, 100 * f) for k, f in iv.categories.items())
    if len(c.found) != 1:
        return "%d crossings of the fit (draws: %s)" % (len(c.found), shares)
    return "%.3f [%.3f, %.3f] (draws: %s)" % (iv.value, c.lo, c.hi, shares)


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    tables = Tables(os.path.dirname(os.path.dirname(os.path.abspath(args.input))))
    defaults, accountings = registered()
    feeds = sorted({r["dynamic.feed"] for r in rows}) if rp.has(rows, "dynamic.feed") else [None]
    fig, axes = rp.subplots(len(ROWS), len(feeds), panel_w=5.0, panel_h=3.6)
    for c, feed in enumerate(feeds):
        sub = [r for r in rows if feed is None or r["dynamic.feed"] == feed]
        sc = rp.sort_by([r for r in sub if r["detp.engine"] == "sphere-cache"], "dynamic.ratio")
        di = rp.sort_by([r for r in sub if r["detp.engine"] == "disc-index"], "dynamic.ratio")
        x = rp.col(sc, "dynamic.ratio")
        for k, (acc, what) in enumerate(ROWS):
            ax = axes[k][c]
            cr, m_sc, m_di = crossing(tables, sc, di, accountings[acc]["dynamic"], defaults)
            ax.plot(x, m_sc, "o", color="C0", ms=4, label="sphere cache")
            ax.plot(x, m_di, "s", color="C1", ms=4, label="disc index")
            if len(cr.found) == 1:
                ax.axvline(cr.interval.value, color="C3", ls="--", lw=1, label="crossover")
                ax.axvspan(cr.lo, cr.hi, color="C3", alpha=0.1, lw=0)
            ax.axvline(0.35, color="0.4", ls=":", lw=1, label="Theorem 2: 0.35")
            print("feed %s, %s: crossover %s" % (feed, acc, text(cr)))
            if acc == "paper":
                ax.plot(x, rp.col(sc, "dynamic_tests_theory_sphere_cache"), "-", color="C0", lw=0.9,
                        label="8.08·n_R·(r_D/r_0)²·∛n_D")
                ax.plot(x, rp.col(sc, "dynamic_tests_theory_disc_index"), "-", color="C1", lw=0.9, label="n_R·∛n_D")
                ax.set_title("feed: %s" % (feed or "as run"), fontsize=10)
            rp.log_scale(ax, x=True, y=True)
            ax.set_xlabel("r_D / r_0")
            ax.set_ylabel(what)
            ax.legend(fontsize=6)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
