#!/usr/bin/env python3
"""Sphere cache vs disc indexing against Theorem 1 (experiment detp-engines-cost).

Theorem 1 counts tests: sphere cache T = t·n_R/Q²·(∛n_P − 1)/(1 − Q) + (4/3)·u·n_R·∛n_P, disc indexing
T = u·n_R·∛n_P. Left: counted tests over Theorem 1's count, against n_R·∛n_P, per engine. Middle: wall
time against the cost the counted tests imply, t·(ray–sphere tests) + u·(ray–disc tests) for the sphere
cache and u_idx·(ray–disc tests) + v·(nodes visited) for each index, with t, u, u_idx, v fitted here by
least squares; the fit and its residuals are printed and shown. Right: the residuals in %.
"""

import numpy as np

import raycost_plot as rp

NAME = "detp-engines-cost"
REQUIRED = ["detp.photons", "detp.points", "detp.index", "segments", "points", "ray_sphere_tests",
            "ray_disc_tests", "tests_sphere_cache", "tests_sphere_cache_theory", "cost_sphere_cache_s",
            "tests_disc_index", "tests_disc_index_theory", "nodes_disc_index", "cost_disc_index_s"]


def fit(x_cols, y):
    """Least squares y ≈ X·c with no intercept; returns c and relative residuals."""
    x = np.column_stack(x_cols)
    c, *_ = np.linalg.lstsq(x, y, rcond=None)
    return c, (x @ c - y) / y


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    nr = np.array(rp.col(rows, "segments"))
    npts = np.array(rp.col(rows, "points"))
    size = nr * np.cbrt(npts)
    # The sphere cache runs the same way whatever index the point uses: fit on every row.
    sc_t = np.array(rp.col(rows, "cost_sphere_cache_s"))
    (t, u), sc_res = fit([np.array(rp.col(rows, "ray_sphere_tests")), np.array(rp.col(rows, "ray_disc_tests"))], sc_t)
    fig, axes = rp.subplots(1, 3, panel_w=5.2, panel_h=4.2)
    ax_c, ax_t, ax_r = axes[0]
    ax_c.plot(size, np.array(rp.col(rows, "tests_sphere_cache")) / np.array(rp.col(rows, "tests_sphere_cache_theory")),
              "o", color="C0", label="sphere cache")
    lines = ["sphere cache: t = %.3g ns/ray–sphere test, u = %.3g ns/ray–disc test, residuals max %.0f %%"
             % (t * 1e9, u * 1e9, 100 * np.max(np.abs(sc_res)))]
    ax_t.plot(t * np.array(rp.col(rows, "ray_sphere_tests")) + u * np.array(rp.col(rows, "ray_disc_tests")), sc_t,
              "o", color="C0", label="sphere cache")
    ax_r.plot(size, 100 * sc_res, "o", color="C0", label="sphere cache")
    for j, index in enumerate(sorted({r["detp.index"] for r in rows})):
        sub = [r for r in rows if r["detp.index"] == index]
        s = np.array(rp.col(sub, "segments")) * np.cbrt(np.array(rp.col(sub, "points")))
        y = np.array(rp.col(sub, "cost_disc_index_s"))
        tests = np.array(rp.col(sub, "tests_disc_index"))
        nodes = np.array(rp.col(sub, "nodes_disc_index"))
        (ui, v), res = fit([tests, nodes], y)
        color = "C%d" % (j + 1)
        ax_c.plot(s, tests / np.array(rp.col(sub, "tests_disc_index_theory")), "s", color=color,
                  label="disc index (%s)" % index)
        ax_t.plot(ui * tests + v * nodes, y, "s", color=color, label="disc index (%s)" % index)
        ax_r.plot(s, 100 * res, "s", color=color, label="disc index (%s)" % index)
        lines.append("disc index (%s): u = %.3g ns/ray–disc test, v = %.3g ns/node, residuals max %.0f %%"
                     % (index, ui * 1e9, v * 1e9, 100 * np.max(np.abs(res))))
    for line in lines:
        print(line)
    ax_c.axhline(1, color="black", lw=0.8)
    ax_c.set_xscale("log")
    ax_c.set_yscale("log")
    ax_c.set_xlabel("n_R·∛n_P")
    ax_c.set_ylabel("counted tests / Theorem 1 (t = u = 1)")
    ax_c.legend(fontsize=7)
    lim = [min(ax_t.get_xlim()[0], ax_t.get_ylim()[0]), max(ax_t.get_xlim()[1], ax_t.get_ylim()[1])]
    ax_t.plot(lim, lim, color="black", lw=0.8)
    ax_t.set_xscale("log")
    ax_t.set_yscale("log")
    ax_t.set_xlabel("cost implied by counted tests at fitted constants, s")
    ax_t.set_ylabel("measured wall time, s")
    ax_t.legend(fontsize=7)
    ax_r.axhline(0, color="black", lw=0.8)
    ax_r.set_xscale("log")
    ax_r.set_xlabel("n_R·∛n_P")
    ax_r.set_ylabel("fit residual, %")
    ax_r.legend(fontsize=7)
    fig.suptitle("\n".join(lines), fontsize=8)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
