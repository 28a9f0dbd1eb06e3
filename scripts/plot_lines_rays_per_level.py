#!/usr/bin/env python3
"""Rays held per sphere-cache level against integral geometry (experiment lines-rays-per-level).

μ-random lines through the unit ball: a sphere of radius r_i = Q^i inside the ball holds
n_R·Q^(2i) rays on average (area ratio), wherever it sits. Levels are built around points uniform in
the ball, so spheres near the rim stick out of it and hold fewer; the dashed line averages the lens
law over centres uniform in the ball (an approximation). Left: rays per level, all spheres (circles)
and only those inside the ball (squares), mean ± 95 % CI across replicas, log y, one colour per Q.
Right: (measured − n_R·Q^(2i)) / n_R·Q^(2i) in %, for all spheres and for those inside the ball.
One series per Q and list mode: the paper's cache (inherited lists: a child rebuilt around a point
sticks out of its parent and holds only the parent's rays that meet it) and raycost's exact lists.
"""

import raycost_plot as rp

NAME = "lines-rays-per-level"
REQUIRED = ["level", "rays_level_mean", "rays_level_se", "rays_level_theory", "rays_level_theory_clipped",
            "rays_level_inside_mean", "rays_level_inside_se"]


def plot(args):
    _, levels = rp.with_params(args.input, "levels", REQUIRED)
    # One series per Q and list mode (the paper's inherited lists and raycost's exact lists).
    by = ["detp.q"] + (["detp.list_mode"] if rp.has(levels, "detp.list_mode") else [])
    keys, groups = rp.group_by(levels, *by)
    fig, axes = rp.subplots(1, 2, panel_w=6.0, panel_h=4.4)
    ax, ax_e = axes[0]
    notes = []
    for j, (value, grp) in enumerate(groups.items()):
        grp = [r for r in rp.sort_by(grp, "level") if (r.get("rays_level_n") or 0) > 0]
        color = "C%d" % j
        label = rp.group_label(keys, value) if keys else "measured"
        label = label.replace("detp.q = ", "Q = ").replace("detp.list_mode = ", "") + (" lists" if len(by) > 1 else "")
        rp.measured(ax, grp, "level", "rays_level", color=color, label=label + ", all spheres (mean ± 95 % CI)")
        inside = [r for r in grp if (r.get("rays_level_inside_n") or 0) > 0]
        rp.measured(ax, inside, "level", "rays_level_inside", color=color, marker="s", mfc="none",
                    label=label + ", spheres inside the ball")
        if value[-1] != "inherited":
            rp.theory(ax, grp, "level", "rays_level_theory", color=color, label="n_R·Q^(2i)")
            rp.theory(ax, grp, "level", "rays_level_theory_clipped", color=color, ls="--",
                      label="lens-clipped law, centres uniform in the ball")
        for rows, metric, ls, name in ((grp, "rays_level", "o-", "all spheres"),
                                       (inside, "rays_level_inside", "s--", "inside the ball")):
            err = [100.0 * (m - t) / t for m, t in zip(rp.col(rows, metric + "_mean"),
                                                        rp.col(rows, "rays_level_theory"))]
            ax_e.plot(rp.col(rows, "level"), err, ls, color=color, ms=3.5, lw=0.9, mfc="none",
                      label="%s, %s" % (label, name))
        nine = [r for r in grp if r["level"] == 9]
        if nine:
            r = nine[0]
            notes.append("%s: level 9 holds %.2f ± %.2f rays (inside the ball %.2f ± %.2f); n_R·Q^18 = %.2f" % (
                label, r["rays_level_mean"], rp.ci95(r, "rays_level"), r.get("rays_level_inside_mean") or float("nan"),
                (rp.ci95(r, "rays_level_inside") if r.get("rays_level_inside_se") is not None else float("nan")), r["rays_level_theory"]))
    rp.log_scale(ax, y=True)
    ax.set_xlabel("level i (radius r_0·Q^i)")
    ax.set_ylabel("rays held by a level-i sphere")
    ax.axhline(100, color="0.5", lw=0.8, ls=":")
    ax.legend(fontsize=6, loc="upper right")
    ax_e.axhline(0, color="black", lw=0.8)
    ax_e.set_xlabel("level i")
    ax_e.set_ylabel("(measured − n_R·Q^(2i)) / n_R·Q^(2i), %")
    ax_e.legend(fontsize=7)
    if notes:
        rp.text_box(ax, "\n".join(notes), loc="lower left", fontsize=6)
    fig.suptitle("Rays per sphere-cache level, μ-random lines in the unit sphere", fontsize=11)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
