#!/usr/bin/env python3
"""Rays per sphere-cache level on the Cornell box against the uniform-line law (experiment
cornell-levels; the paper's Figures 6–7 for its real scenes).

Left: rays held by a level-i sphere (mean ± 95 % CI across replicas, log y) and n_R·(r_i/r_0)² with
n_R the stored segments. Right: the percentage error of the law per level, with the paper's ±5 %.
"""

import raycost_plot as rp

NAME = "cornell-levels"
REQUIRED = ["level", "radius", "rays_level_mean", "rays_level_se", "rays_level_theory"]


def plot(args):
    _, levels = rp.with_params(args.input, "levels", REQUIRED)
    levels = [r for r in rp.sort_by(levels, "level") if (r.get("rays_level_n") or 0) > 0]
    fig, axes = rp.subplots(1, 2, panel_w=6.0, panel_h=4.2)
    ax, ax_e = axes[0]
    rp.measured(ax, levels, "level", "rays_level", label="measured (mean ± 95 % CI)")
    rp.theory(ax, levels, "level", "rays_level_theory", label="n_R·(r_i/r_0)², uniform lines")
    rp.log_scale(ax, y=True)
    ax.set_xlabel("level i")
    ax.set_ylabel("rays held by a level-i sphere")
    ax.legend(fontsize=8)
    err = [100 * (t - m) / m for m, t in zip(rp.col(levels, "rays_level_mean"), rp.col(levels, "rays_level_theory"))]
    ax_e.plot(rp.col(levels, "level"), err, "o-", color="C3")
    ax_e.axhspan(-5, 5, color="0.9", label="±5 % (the paper's 'most levels')")
    ax_e.axhline(0, color="black", lw=0.8)
    ax_e.set_xlabel("level i")
    ax_e.set_ylabel("(law − measured) / measured, %")
    ax_e.legend(fontsize=8)
    for r, e in zip(levels, err):
        print("level %2d radius %9.3f measured %10.1f law %10.1f error %+6.1f %%" % (
            r["level"], r["radius"], r["rays_level_mean"], r["rays_level_theory"], e))
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
