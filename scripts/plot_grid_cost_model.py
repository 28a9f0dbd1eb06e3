#!/usr/bin/env python3
"""The query-time model t = N_I·T_I + N_S·T_S against the timed query (experiment grid-cost-model).

x = cell width a. Left: measured time_per_ray_s against time_model_s (theory counts × the
microbenchmarked T_I, T_S) and time_counts_model_s (measured counts × T_I, T_S), and the fit
time_per_ray_s ≈ n_i_mb_mean·T_I + n_s_mean·T_S (raycost_stats.fit_costs: non-negative least squares on
relative residuals, the one cost fit raycost has, held equal to the Rust side's on shared cases); the
argmin of the measured time and of each model are marked. The fitted T_I, T_S are printed beside the microbenchmarked t_i_s, t_s_s.
Right: the measured counts E[N_I] (mailbox) and E[N_S] against their theory, which drive the model.
"""

import math

import raycost_plot as rp
import raycost_stats as S

NAME = "grid-cost-model"
REQUIRED = ["grid.cell_width", "time_per_ray_s", "time_model_s", "time_counts_model_s",
            "n_i_mb_mean", "n_s_mean", "t_i_s", "t_s_s"]


def argmin(xs, ys):
    pts = [(y, x) for x, y in zip(xs, ys) if y == y]
    return min(pts)[1] if pts else math.nan


def fit_costs(rows):
    """time_per_ray_s ≈ N_I·T_I + N_S·T_S (no intercept) by the shared cost fit. Returns (T_I, T_S)."""
    ok = [r for r in rows
          if all(math.isfinite(r[c]) for c in ("n_i_mb_mean", "n_s_mean", "time_per_ray_s"))
          and r["time_per_ray_s"] > 0]
    if len(ok) < 2:
        return math.nan, math.nan
    fit = S.fit_costs([[r["n_i_mb_mean"] for r in ok], [r["n_s_mean"] for r in ok]],
                      [r["time_per_ray_s"] for r in ok])
    if fit is None:
        return math.nan, math.nan
    return fit[0][0], fit[0][1]


def plot(args):
    rows = rp.sort_by(rp.read_csv(args.input, REQUIRED), "grid.cell_width")
    x = "grid.cell_width"
    xs = rp.col(rows, x)
    t_i_fit, t_s_fit = fit_costs(rows)
    for r in rows:
        r["fit_s"] = r["n_i_mb_mean"] * t_i_fit + r["n_s_mean"] * t_s_fit

    fig, axes = rp.subplots(1, 2, panel_w=6.2, panel_h=4.6)
    ax, ax_c = axes[0]
    us = 1e6
    series = [
        ("time_per_ray_s", "measured time per ray", "o-", "C0"),
        ("time_model_s", "time_model_s (theory counts × T_I, T_S)", "-", "black"),
        ("time_counts_model_s", "time_counts_model_s (measured counts × T_I, T_S)", "--", "C2"),
        ("fit_s", "least-squares fit (measured counts × fitted T_I, T_S)", ":", "C3"),
    ]
    for column, label, style, color in series:
        ys = [v * us for v in rp.col(rows, column)]
        ax.plot(xs, ys, style, color=color, label=label, ms=5, lw=1.4)
        best = argmin(xs, ys)
        if best == best:
            y_best = ys[xs.index(best)]
            ax.plot([best], [y_best], marker="*", ms=14, color=color, mec="white", zorder=4)
    rp.log_scale(ax, x=True, y=True)
    ax.set_xlabel("a  (cell width)")
    ax.set_ylabel("time per ray [µs]")
    ax.set_title("query time vs cell width (★ = argmin)", fontsize=10)
    ax.legend(fontsize=7.5, loc="upper center")
    lo, hi = ax.get_ylim()
    ax.set_ylim(lo, hi * 2.2)
    t_i, t_s = rows[0]["t_i_s"], rows[0]["t_s_s"]
    note = (
        "argmin a: measured %g, time_model %g,\n  counts model %g, fit %g\n"
        "T_I: microbench %.3g ns, fitted %.3g ns\n"
        "T_S: microbench %.3g ns, fitted %.3g ns"
        % (argmin(xs, rp.col(rows, "time_per_ray_s")), argmin(xs, rp.col(rows, "time_model_s")),
           argmin(xs, rp.col(rows, "time_counts_model_s")), argmin(xs, rp.col(rows, "fit_s")),
           t_i * 1e9, t_i_fit * 1e9,
           t_s * 1e9, t_s_fit * 1e9)
    )
    rp.text_box(ax, note, loc="lower left", fontsize=7.5)

    for metric, color, marker in (("n_i_mb", rp.COLORS["measured_mb"], "s"), ("n_s", "C2", "^")):
        rp.measured(ax_c, rows, x, metric, color=color, marker=marker, label="%s measured" % metric)
        if rp.has(rows, metric + "_theory"):
            rp.theory(ax_c, rows, x, metric + "_theory", color=color, ls=":",
                      label="%s_theory" % metric)
    rp.log_scale(ax_c, x=True, y=True)
    ax_c.set_xlabel("a  (cell width)")
    ax_c.set_ylabel("mean count per ray")
    ax_c.set_title("the counts behind the model", fontsize=10)
    ax_c.legend(fontsize=8, loc="upper center")
    lo, hi = ax_c.get_ylim()
    ax_c.set_ylim(lo, hi * 3)
    spheres = rp.spec_value(args.input, "scene.spheres", rows[0])
    if spheres is not None:
        rp.text_box(ax_c, "finite scene, n = %g spheres" % spheres, loc="lower left", fontsize=7.5)

    for a in axes[0]:
        a.grid(True, which="major", alpha=0.3)
        rp.pad_log_limits(a, xs, factor=1.2)
    fig.suptitle("%s: t = N_I·T_I + N_S·T_S against the timed query" % NAME, fontsize=11, y=1.0)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
