#!/usr/bin/env python3
"""Rays held per sphere-cache level against integral geometry (experiment lines-rays-per-level).

μ-random lines through the unit ball: a sphere of radius r_i = Q^i inside the root holds
n_R·Q^(2i) rays on average (area ratio). Levels are built around points uniform in the ball, so deep
spheres near the rim stick out of it; the dashed line averages the exact lens law over centres uniform
in the ball. Left: rays per level (mean ± 95 % CI across replicas, log y) with both laws, one colour per
Q. Right: (measured − law)/law in %, for both laws. Reads NAME.csv and NAME.levels.csv.
"""

import raycost_plot as rp

NAME = "lines-rays-per-level"
REQUIRED = ["level", "rays_level_mean", "rays_level_se", "rays_level_theory", "rays_level_theory_clipped"]


def plot(args):
    _, levels = rp.with_params(args.input, "levels", REQUIRED)
    keys, groups = rp.group_by(levels, "detp.q")
    fig, axes = rp.subplots(1, 2, panel_w=6.0, panel_h=4.4)
    ax, ax_e = axes[0]
    notes = []
    for j, (value, grp) in enumerate(groups.items()):
        grp = [r for r in rp.sort_by(grp, "level") if (r.get("rays_level_n") or 0) > 0]
        color = "C%d" % j
        label = rp.group_label(keys, value) if keys else "measured"
        rp.measured(ax, grp, "level", "rays_level", color=color, label=label + " (mean ± 95 % CI)")
        rp.theory(ax, grp, "level", "rays_level_theory", color=color, label="n_R·Q^(2i)")
        rp.theory(ax, grp, "level", "rays_level_theory_clipped", color=color, ls="--",
                  label="lens-clipped law, centres uniform in the ball")
        for col, ls, name in (("rays_level_theory", "o-", "vs n_R·Q^(2i)"),
                              ("rays_level_theory_clipped", "s--", "vs clipped")):
            err = [100.0 * (m - t) / t for m, t in zip(rp.col(grp, "rays_level_mean"), rp.col(grp, col))]
            ax_e.plot(rp.col(grp, "level"), err, ls, color=color, ms=3.5, lw=0.9,
                      label="%s, %s" % (label, name))
        nine = [r for r in grp if r["level"] == 9]
        if nine:
            r = nine[0]
            notes.append("%s: level 9 holds %.1f ± %.1f rays (n_R·Q^18 = %.1f; clipped %.1f)" % (
                label, r["rays_level_mean"], rp.Z95 * r["rays_level_se"], r["rays_level_theory"],
                r["rays_level_theory_clipped"]))
    rp.log_scale(ax, y=True)
    ax.set_xlabel("level i (radius r_0·Q^i)")
    ax.set_ylabel("rays held by a level-i sphere")
    ax.axhline(100, color="0.5", lw=0.8, ls=":")
    ax.legend(fontsize=7)
    ax_e.axhline(0, color="black", lw=0.8)
    ax_e.set_xlabel("level i")
    ax_e.set_ylabel("(measured − law) / law, %")
    ax_e.legend(fontsize=7)
    if notes:
        rp.text_box(ax, "\n".join(notes), loc="lower left", fontsize=7)
    fig.suptitle("Rays per sphere-cache level, μ-random lines in the unit sphere", fontsize=11)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
