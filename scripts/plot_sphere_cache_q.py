#!/usr/bin/env python3
"""Sphere-cache cost against Q (experiment sphere-cache-q; Proposition 1: optimum Q = 2/3).

Left: counted ray–sphere tests (re-building) and ray–disc tests against Theorem 1's terms
T_R = n_R/Q²·(∛n_P − 1)/(1 − Q) and T_I = (4/3)·n_R·∛n_P (t = u = 1). Right: wall time of the sphere
cache; the measured optimum and 2/3 are marked.
"""

import raycost_plot as rp

NAME = "sphere-cache-q"
REQUIRED = ["detp.q", "ray_sphere_tests", "ray_sphere_tests_theory", "ray_disc_tests",
            "ray_disc_tests_theory", "cost_sphere_cache_s", "tests_sphere_cache", "tests_sphere_cache_theory"]


def plot(args):
    rows = rp.sort_by(rp.read_csv(args.input, REQUIRED), "detp.q")
    fig, axes = rp.subplots(1, 2, panel_w=6.0, panel_h=4.2)
    ax, ax_t = axes[0]
    q = rp.col(rows, "detp.q")
    for col, color, label in (("ray_sphere_tests", "C0", "ray–sphere tests (re-building)"),
                              ("ray_disc_tests", "C1", "ray–disc tests (inner spheres)"),
                              ("tests_sphere_cache", "C2", "total")):
        ax.plot(q, rp.col(rows, col), "o", color=color, label=label + ", measured")
        ax.plot(q, rp.col(rows, col + "_theory"), "-", color=color, lw=1, label=label + ", Theorem 1")
    rp.log_scale(ax, y=True)
    ax.set_xlabel("Q")
    ax.set_ylabel("tests (all replicas)")
    ax.legend(fontsize=7)
    t = rp.col(rows, "cost_sphere_cache_s")
    best = min(range(len(rows)), key=lambda i: t[i])
    tests = rp.col(rows, "tests_sphere_cache")
    best_tests = min(range(len(rows)), key=lambda i: tests[i])
    ax_t.plot(q, t, "o-", color="C3", label="sphere cache wall time")
    for a in (ax, ax_t):
        a.axvline(2.0 / 3.0, color="0.4", ls="--", lw=0.9)
    ax_t.axvline(q[best], color="C3", ls=":", lw=0.9)
    ax_t.set_xlabel("Q")
    ax_t.set_ylabel("seconds")
    rp.text_box(ax_t, "fastest Q = %g, fewest tests at Q = %g\nProposition 1: 2/3" % (q[best], q[best_tests]))
    ax_t.legend(fontsize=7, loc="upper right")
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
