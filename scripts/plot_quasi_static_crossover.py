#!/usr/bin/env python3
"""Theorem 2: dynamic points by the sphere cache vs by a disc index as r_D/r_0 grows (experiment
quasi-static-crossover).

Left: seconds per frame to recompute the dynamic points, each engine (mean ± 95 % CI over frames),
and the measured crossover (where the two curves cross, interpolated in log space). Right: the
counted tests per frame (sphere cache: ray–sphere + ray–disc; disc index: ray–disc) with Theorem 2's
costs for the same n_R and n_D (t = u), whose crossover is 1/√8.08 ≈ 0.35 at n → ∞ and
`crossover_theory` at the run's n_D.
"""

import math

import raycost_plot as rp

NAME = "quasi-static-crossover"
REQUIRED = ["dynamic.ratio", "detp.engine", "dynamic_s_mean", "dynamic_tests_mean", "dynamic_sphere_tests_mean",
            "dynamic_tests_theory_sphere_cache", "dynamic_tests_theory_disc_index", "crossover_theory"]


def crossing(xs, a, b):
    """First x where a − b changes sign (log-linear interpolation), or None."""
    for i in range(1, len(xs)):
        d0, d1 = math.log(a[i - 1]) - math.log(b[i - 1]), math.log(a[i]) - math.log(b[i])
        if d0 <= 0 < d1 or d0 >= 0 > d1:
            return xs[i - 1] + (xs[i] - xs[i - 1]) * d0 / (d0 - d1)
    return None


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    sc = rp.sort_by([r for r in rows if r["detp.engine"] == "sphere-cache"], "dynamic.ratio")
    di = rp.sort_by([r for r in rows if r["detp.engine"] == "disc-index"], "dynamic.ratio")
    fig, axes = rp.subplots(1, 2, panel_w=5.8, panel_h=4.3)
    ax_t, ax_c = axes[0]
    rp.measured(ax_t, sc, "dynamic.ratio", "dynamic_s", label="sphere cache", color="C0")
    rp.measured(ax_t, di, "dynamic.ratio", "dynamic_s", label="disc index", color="C1", marker="s")
    x = rp.col(sc, "dynamic.ratio")
    t_cross = crossing(x, rp.col(sc, "dynamic_s_mean"), rp.col(di, "dynamic_s_mean"))
    sc_tests = [a + b for a, b in zip(rp.col(sc, "dynamic_tests_mean"), rp.col(sc, "dynamic_sphere_tests_mean"))]
    di_tests = rp.col(di, "dynamic_tests_mean")
    c_cross = crossing(x, sc_tests, di_tests)
    th_cross = crossing(x, rp.col(sc, "dynamic_tests_theory_sphere_cache"), rp.col(sc, "dynamic_tests_theory_disc_index"))
    for ax, v, what in ((ax_t, t_cross, "time"), (ax_c, c_cross, "tests")):
        if v:
            ax.axvline(v, color="C3", ls="--", lw=1, label="measured crossover (%s) %.3f" % (what, v))
        ax.axvline(0.35, color="0.4", ls=":", lw=1, label="Theorem 2: 0.35")
    rp.log_scale(ax_t, x=True, y=True)
    ax_t.set_xlabel("r_D / r_0")
    ax_t.set_ylabel("seconds per frame, dynamic points")
    ax_t.legend(fontsize=7)
    ax_c.plot(x, sc_tests, "o", color="C0", label="sphere cache, counted tests")
    ax_c.plot(x, di_tests, "s", color="C1", label="disc index, counted tests")
    ax_c.plot(x, rp.col(sc, "dynamic_tests_theory_sphere_cache"), "-", color="C0", label="8.08·n_R·(r_D/r_0)²·∛n_D")
    ax_c.plot(x, rp.col(sc, "dynamic_tests_theory_disc_index"), "-", color="C1", label="n_R·∛n_D")
    rp.log_scale(ax_c, x=True, y=True)
    ax_c.set_xlabel("r_D / r_0")
    ax_c.set_ylabel("tests per frame, dynamic points")
    ax_c.legend(fontsize=7)
    print("crossover r_D/r_0: measured by time %s, by counted tests %s; Theorem 2 at these n %s (0.35 at n → ∞; crossover_theory column %.3f…%.3f)" % (
        "%.3f" % t_cross if t_cross else "none in range", "%.3f" % c_cross if c_cross else "none in range",
        "%.3f" % th_cross if th_cross else "none", min(rp.col(sc, "crossover_theory")), max(rp.col(sc, "crossover_theory"))))
    for a, b in zip(sc, di):
        print("r_D/r_0 %.2f: sphere cache %.4f s (%.3g tests), disc index %.4f s (%.3g tests), n_D %d" % (
            a["dynamic.ratio"], a["dynamic_s_mean"], a["dynamic_tests_mean"] + a["dynamic_sphere_tests_mean"],
            b["dynamic_s_mean"], b["dynamic_tests_mean"], a["points_dynamic"]))
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
