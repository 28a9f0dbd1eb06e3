#!/usr/bin/env python3
"""Superoptimality E[t(n)] = O(1), measured (experiment grid-scaling).

Finite scenes of n spheres at fixed intensity, eye at the centre; x = scene.spheres (log) in every panel.
Top row: E[N_I] (no mailbox, mailbox) and E[N_S] with 95 % error bars and the infinite-scene predictions
(n_i_theory, n_i_mb_theory, n_s_theory) as dotted lines — flat in n once the scene is many mean free
paths deep; the hit fraction against hit_theory (a finite scene lets rays escape, which is why the counts
rise towards the infinite-scene values); time per ray.
Bottom row: rays/s of the grid and of brute force (small n; bf_mismatches annotated, must be 0);
build time and grid memory against n (log-log) with a slope-1 reference line.
"""

import math

import raycost_plot as rp

NAME = "grid-scaling"
REQUIRED = ["n_i_mean", "n_i_se", "n_s_mean", "n_s_se", "time_per_ray_s", "rays_per_s",
            "build_s", "grid_bytes"]


def n_column(rows, path):
    for c in ("scene.spheres", "spheres"):
        if rp.has(rows, c):
            return c
    raise rp.PlotError("%s: missing required column scene.spheres (or spheres)" % path)


def slope_one(ax, xs, ys, label="slope 1 (∝ n)"):
    """A dashed line of slope 1 on log-log axes through the largest finite point."""
    pts = [(x, y) for x, y in zip(xs, ys) if x == x and y == y and x > 0 and y > 0]
    if not pts:
        return
    x0, y0 = max(pts)
    lo = min(p[0] for p in pts)
    ax.plot([lo, x0], [y0 * lo / x0, y0], ls="--", color="0.5", lw=1, label=label, zorder=1)


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    n = n_column(rows, args.input)
    rows = rp.sort_by(rows, n)
    xs = rp.col(rows, n)

    fig, axes = rp.subplots(2, 3, panel_w=5.0, panel_h=3.9)
    (ax_c, ax_h, ax_t), (ax_r, ax_b, ax_m) = axes

    # counts
    for metric, color, marker in (("n_i", rp.COLORS["measured"], "o"),
                                  ("n_i_mb", rp.COLORS["measured_mb"], "s"),
                                  ("n_s", "C2", "^")):
        if not rp.has(rows, metric + "_mean"):
            continue
        rp.measured(ax_c, rows, n, metric, color=color, marker=marker,
                    label="%s measured" % metric)
        if rp.has(rows, metric + "_theory"):
            rp.theory(ax_c, rows, n, metric + "_theory", color=color, ls=":",
                      label="%s_theory (infinite scene)" % metric)
    rp.log_scale(ax_c, x=True, y=True)
    ax_c.set_ylabel("mean count per ray")
    ax_c.set_title("E[N_I], E[N_S] vs n (flat = O(1))", fontsize=10)
    lo, hi = ax_c.get_ylim()
    ax_c.set_ylim(lo, hi * 6)
    ax_c.legend(fontsize=6.5, loc="upper left", ncol=2)
    rho = rp.spec_value(args.input, "scene.intensity", rows[-1])
    mfp = rows[-1].get("t_hit_theory")
    if isinstance(rho, (int, float)) and isinstance(mfp, float) and rho > 0:
        radius = (3 * xs[-1] / (4 * math.pi * rho)) ** (1 / 3)
        rp.text_box(ax_c, "mean free path 1/(ρπr²) = %.3g\nscene radius at n = %g: %.3g (%.2g mfp)"
                    % (mfp, xs[-1], radius, radius / mfp), loc="lower right", fontsize=7)

    # hit fraction
    if rp.has(rows, "hit_mean"):
        rp.measured(ax_h, rows, n, "hit", label="hit measured")
        if rp.has(rows, "hit_theory"):
            rp.theory(ax_h, rows, n, "hit_theory", label="hit_theory")
        ax_h.set_ylim(0, 1.05)
        ax_h.legend(fontsize=8, loc="upper left")
    else:
        ax_h.text(0.5, 0.5, "no hit column", ha="center", transform=ax_h.transAxes)
    rp.log_scale(ax_h, x=True)
    ax_h.set_ylabel("fraction of rays that hit")
    ax_h.set_title("hit fraction (finite scene: rays escape)", fontsize=10)

    # time per ray
    ax_t.plot(xs, rp.col(rows, "time_per_ray_s"), "o-", color="C0", label="grid time per ray")
    rp.log_scale(ax_t, x=True, y=True)
    ax_t.set_ylabel("time per ray [s]")
    ax_t.set_title("query time per ray", fontsize=10)
    ax_t.legend(fontsize=8)

    # rays/s, grid vs brute force
    ax_r.plot(xs, rp.col(rows, "rays_per_s"), "o-", color="C0", label="grid rays/s")
    if rp.has(rows, "bf_rays_per_s"):
        bf = [(x, y) for x, y in zip(xs, rp.col(rows, "bf_rays_per_s")) if y == y and y > 0]
        if bf:
            ax_r.plot([p[0] for p in bf], [p[1] for p in bf], "s-", color="C3",
                      label="brute force rays/s")
            x_last, y_last = bf[0][0], bf[0][1]
            ax_r.plot([bf[0][0], bf[-1][0]], [y_last, y_last * x_last / bf[-1][0]], ls="--",
                      color="0.5", lw=1, label="slope −1 (∝ 1/n)")
    if rp.has(rows, "bf_mismatches"):
        checked = [(x, m, r.get("bf_rays") or 0) for x, m, r in zip(xs, rp.col(rows, "bf_mismatches"), rows)
                   if (r.get("bf_rays") or 0) > 0]
        if checked:
            total = sum(m for _, m, _ in checked if m == m)
            text = "bf_mismatches: %d in %d checked rays (n ≤ %g)" % (
                total, sum(c for _, _, c in checked), max(x for x, _, _ in checked))
            rp.text_box(ax_r, text + ("" if total == 0 else "  ← must be 0"), loc="lower left",
                        fontsize=7.5)
    rp.log_scale(ax_r, x=True, y=True)
    ax_r.set_ylabel("rays per second")
    ax_r.set_title("throughput: grid vs brute force", fontsize=10)
    ax_r.legend(fontsize=8, loc="upper right")

    # build time and memory, each against a slope-1 reference
    for ax, column, ylabel, title in (
        (ax_b, "build_s", "grid build time [s]", "build time vs n"),
        (ax_m, "grid_bytes", "grid memory [bytes]", "grid memory vs n"),
    ):
        ys_c = rp.col(rows, column)
        ax.plot(xs, ys_c, "o-", color="C0", label=column)
        slope_one(ax, xs, ys_c)
        rp.log_scale(ax, x=True, y=True)
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize=10)
        ax.legend(fontsize=8, loc="upper left")

    for ax in axes.flat:
        ax.grid(True, which="major", alpha=0.3)
        rp.pad_log_limits(ax, xs, factor=1.5)
    for ax in axes[1]:
        ax.set_xlabel("n  (scene.spheres)")
    for ax in axes[0]:
        ax.set_xlabel("n  (scene.spheres)")
    fig.suptitle("%s: cost per ray against the number of spheres n at fixed intensity" % NAME,
                 fontsize=11, y=1.0)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
