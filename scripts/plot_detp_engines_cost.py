#!/usr/bin/env python3
"""Sphere cache vs disc indexing against Theorem 1 (experiment detp-engines-cost).

Theorem 1 counts tests: sphere cache T = t·n_R/Q²·(∛n_P − 1)/(1 − Q) + (4/3)·u·n_R·∛n_P, disc indexing
T = u·n_R·∛n_P. Left: counted tests over Theorem 1's count, against n_R·∛n_P, per engine. Middle: wall
time against the cost the counted tests imply, t·(ray–sphere tests) + u·(ray–disc tests) for the sphere
cache and u_idx·(ray–disc tests) + v·(nodes visited) for each index, each plus a cost per segment
(building the root list, walking the index), fitted here by non-negative least squares on relative
residuals (raycost_stats.engine_cost_fits), with 95 % CIs by a bootstrap that resamples the rows (the fit's misfit inside them) and the replicas'
timings; the fit and its residuals are printed and shown. Right: the residuals in %.
"""

import numpy as np

import raycost_plot as rp
from raycost_stats import engine_cost_fits, rays_copied

NAME = "detp-engines-cost"
REQUIRED = ["detp.photons", "detp.points", "detp.index", "segments", "points", "ray_sphere_tests",
            "ray_disc_tests", "tests_sphere_cache", "tests_sphere_cache_theory", "cost_sphere_cache_s",
            "tests_disc_index", "tests_disc_index_theory", "nodes_disc_index", "cost_disc_index_s"]


def plot(args):
    rows, levels = rp.with_params(args.input, "levels", ["point", "builds_level", "rays_level_mean"])
    rows = [r for r in rows if all(c in r for c in REQUIRED)] or rp.read_csv(args.input, REQUIRED)
    held = rays_copied(levels)
    fits = engine_cost_fits(rows, levels)
    nr = np.array(rp.col(rows, "segments"))
    npts = np.array(rp.col(rows, "points"))
    size = nr * np.cbrt(npts)
    sc_t = np.array(rp.col(rows, "cost_sphere_cache_s"))
    copied = np.array([held.get(r["point"], 0.0) for r in rows])
    (c_sc, t, u, h), sc_res, sc_ci = fits["sphere-cache"][:3]
    sc_res = np.array(sc_res)
    fig, axes = rp.subplots(1, 3, panel_w=5.2, panel_h=4.2)
    ax_c, ax_t, ax_r = axes[0]
    ax_c.plot(size, np.array(rp.col(rows, "tests_sphere_cache")) / np.array(rp.col(rows, "tests_sphere_cache_theory")),
              "o", color="C0", label="sphere cache")
    ns = lambda lo_hi: "[%.3g, %.3g]" % (lo_hi[0] * 1e9, lo_hi[1] * 1e9)  # noqa: E731
    lines = ["sphere cache: %.3g ns/segment + t = %.3g %s ns/ray–sphere test + u = %.3g %s ns/ray–disc test + "
             "%.3g ns/ray copied; residuals max %.0f %%, rms %.0f %%" % (
                 c_sc * 1e9, t * 1e9, ns(sc_ci[1]), u * 1e9, ns(sc_ci[2]), h * 1e9,
                 100 * np.max(np.abs(sc_res)), 100 * np.sqrt(np.mean(sc_res ** 2)))]
    ax_t.plot(c_sc * nr + t * np.array(rp.col(rows, "ray_sphere_tests")) + u * np.array(rp.col(rows, "ray_disc_tests"))
              + h * copied, sc_t, "o", color="C0", label="sphere cache")
    ax_r.plot(size, 100 * sc_res, "o", color="C0", label="sphere cache")
    for j, index in enumerate(sorted({r["detp.index"] for r in rows})):
        sub = [r for r in rows if r["detp.index"] == index]
        s = np.array(rp.col(sub, "segments")) * np.cbrt(np.array(rp.col(sub, "points")))
        y = np.array(rp.col(sub, "cost_disc_index_s"))
        tests = np.array(rp.col(sub, "tests_disc_index"))
        nodes = np.array(rp.col(sub, "nodes_disc_index"))
        seg = np.array(rp.col(sub, "segments"))
        (ci, ui, v), res, cis = fits["disc-index (%s)" % index][:3]
        res = np.array(res)
        color = "C%d" % (j + 1)
        ax_c.plot(s, tests / np.array(rp.col(sub, "tests_disc_index_theory")), "s", color=color,
                  label="disc index (%s)" % index)
        ax_t.plot(ci * seg + ui * tests + v * nodes, y, "s", color=color, label="disc index (%s)" % index)
        ax_r.plot(s, 100 * res, "s", color=color, label="disc index (%s)" % index)
        lines.append("disc index (%s): %.3g ns/segment + u = %.3g %s ns/ray–disc test + v = %.3g %s ns/node; "
                     "residuals max %.0f %%, rms %.0f %%" % (index, ci * 1e9, ui * 1e9, ns(cis[1]), v * 1e9, ns(cis[2]),
                                                          100 * np.max(np.abs(res)), 100 * np.sqrt(np.mean(res ** 2))))
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
