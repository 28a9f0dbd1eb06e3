#!/usr/bin/env python3
"""E[N_I] and E[N_S] against the cell width, measured vs theory (experiment grid-cell-width).

Top row: the ray-sphere tests E[N_I] against a/r (log-log), without mailboxing (n_i) and with it
(n_i_mb), as mean ± 95 % CI; Result 3.1's band (n_i_lower..n_i_upper) shaded; the sharper predictors
n_i_theory and n_i_mb_theory as lines; the cylinder-only term n_i_plain_theory dashed.
Middle row: the cell steps E[N_S] measured vs n_s_theory; bottom row: (measured − theory)/se for N_S,
which should stay within ±2.58 (99 %).
One column per (scene.intensity, grid.eye) combination present in the CSV.
"""

import math
import sys

import raycost_plot as rp

NAME = "grid-cell-width"
GROUP_KEYS = ("scene.intensity", "grid.eye", "scene.radius")
REQUIRED = [
    "grid.cell_width",
    "n_i_mean",
    "n_i_se",
    "n_i_mb_mean",
    "n_i_mb_se",
    "n_i_lower",
    "n_i_upper",
    "n_i_theory",
    "n_i_mb_theory",
    "n_s_mean",
    "n_s_se",
    "n_s_theory",
]


def max_z(rows, metric):
    """Max |measured − theory| / se over rows."""
    zs = [
        abs(m - t) / s
        for m, t, s in zip(rp.col(rows, metric + "_mean"), rp.col(rows, metric + "_theory"),
                           rp.col(rows, metric + "_se"))
        if s > 0
    ]
    return max(zs) if zs else math.nan


def plot(args, title=None, x="a/r", group_keys=GROUP_KEYS, band_name="Result 3.1"):
    """Draw the figure. x = "a/r" (cell width over the spec's sphere radius) or "a" (cell width,
    for scenes with radius classes); one column per combination of group_keys present."""
    rows = rp.read_csv(args.input, REQUIRED)
    for r in rows:
        if x == "a":
            r["a_over_r"] = r["grid.cell_width"]
            continue
        radius = rp.spec_value(args.input, "scene.radius", r)
        if not isinstance(radius, (int, float)) or radius <= 0:
            raise rp.PlotError(
                "%s: cannot find the sphere radius (no scene.radius column and no "
                "[spec.base.scene] radius in the .meta.toml)" % args.input
            )
        r["a_over_r"] = r["grid.cell_width"] / radius
    xlabel = "a  (cell width)" if x == "a" else "a / r  (cell width / sphere radius)"
    keys, groups = rp.group_by(rows, *group_keys)
    ncols = len(groups)

    fig = rp.plt.figure(figsize=(max(5.2 * ncols, 6.5), 10.0))
    gs = fig.add_gridspec(3, ncols, height_ratios=[3.2, 2.0, 1.1], hspace=0.08, wspace=0.25)
    all_ratio, all_err, all_err_mb = [], [], []
    handles = None
    for j, (value, grp) in enumerate(groups.items()):
        grp = rp.sort_by(grp, "a_over_r")
        ax = fig.add_subplot(gs[0, j])
        ax_s = fig.add_subplot(gs[1, j], sharex=ax)
        ax_d = fig.add_subplot(gs[2, j], sharex=ax)

        rp.band(ax, grp, "a_over_r", "n_i_lower", "n_i_upper", label="%s band" % band_name)
        if rp.has(grp, "n_i_plain_theory"):
            rp.theory(ax, grp, "a_over_r", "n_i_plain_theory", color=rp.COLORS["plain"], ls="--",
                      label="n_i_plain_theory (1 + E[N_S])·ρ|o(a,r)|")
        rp.theory(ax, grp, "a_over_r", "n_i_theory", color=rp.COLORS["theory"],
                  label="n_i_theory (no mailbox)")
        rp.theory(ax, grp, "a_over_r", "n_i_mb_theory", color=rp.COLORS["theory_mb"],
                  label="n_i_mb_theory (mailbox)")
        rp.measured(ax, grp, "a_over_r", "n_i", label="n_i measured, no mailbox (± 95 % CI)")
        rp.measured(ax, grp, "a_over_r", "n_i_mb", color=rp.COLORS["measured_mb"], marker="s",
                    label="n_i_mb measured, mailbox (± 95 % CI)")
        rp.log_scale(ax, x=True, y=True)
        rp.pad_log_limits(ax, rp.col(grp, "a_over_r"))
        ax.set_title(rp.group_label(keys, value) if keys else (title or NAME), fontsize=10)
        if j == 0:
            ax.set_ylabel("E[N_I]  (ray-sphere tests)")
            handles = ax.get_legend_handles_labels()

        ratios = [u / l for l, u in zip(rp.col(grp, "n_i_lower"), rp.col(grp, "n_i_upper")) if l > 0]
        err = rp.rel_err(grp, "n_i")
        err_mb = rp.rel_err(grp, "n_i_mb")
        all_ratio += ratios
        all_err.append(err)
        all_err_mb.append(err_mb)
        outside = [
            "%s %s at %s=%g" % (m, r[m + "_band"], x, r["a_over_r"])
            for m in ("n_i", "n_i_mb")
            for r in grp
            if r.get(m + "_band") not in (None, "inside")
        ]
        note = (
            "band width upper/lower: %.1f – %.1f\n"
            "max |meas − pred| / pred:\n"
            "  n_i_theory %.1f %% (%.1f se)\n  n_i_mb_theory %.1f %% (%.1f se)"
            % (min(ratios), max(ratios), 100 * err, max_z(grp, "n_i"), 100 * err_mb, max_z(grp, "n_i_mb"))
        )
        if outside:
            note += "\noutside band: " + "; ".join(outside[:3]) + (" …" if len(outside) > 3 else "")
        rp.text_box(ax, note, loc="upper left")
        # leave room for the note above the data
        lo, hi = ax.get_ylim()
        ax.set_ylim(lo, hi * 15)

        rp.theory(ax_s, grp, "a_over_r", "n_s_theory", label="n_s_theory")
        rp.measured(ax_s, grp, "a_over_r", "n_s", label="n_s measured (± 95 % CI)")
        rp.log_scale(ax_s, y=True)
        if j == 0:
            ax_s.set_ylabel("E[N_S]  (cell steps)")
        ax_s.legend(fontsize=8, loc="upper right")
        s_err = rp.rel_err(grp, "n_s")
        rp.text_box(ax_s, "max rel. error %.2f %%" % (100 * s_err), loc="lower left")

        dev = rp.deviation(ax_d, grp, "a_over_r", "n_s")
        n_out = sum(1 for d in dev if d == d and abs(d) > rp.Z99)
        ax_d.set_xlabel(xlabel)
        if j != 0:
            ax_d.set_ylabel("")
        if n_out:
            rp.text_box(ax_d, "%d point(s) beyond ±2.58" % n_out, loc="lower left", fontsize=7)
        for a in (ax, ax_s):
            a.tick_params(which="both", labelbottom=False)
        for a in (ax, ax_s, ax_d):
            a.grid(True, which="major", alpha=0.3)

    fig.legend(*handles, loc="lower center", bbox_to_anchor=(0.5, 0.905), ncol=3 if ncols > 1 else 2, fontsize=8.5,
               frameon=False)
    finite = lambda xs: [x for x in xs if x == x]  # noqa: E731
    fig.suptitle(
        "%s: %s's band is a factor %.0f–%.0f wide (upper/lower);%s"
        "the sharper predictors are within %.1f %% (no mailbox) and %.1f %% (mailbox)"
        % (title or NAME, band_name, min(all_ratio), max(all_ratio), " " if ncols > 2 else "\n", 100 * max(finite(all_err) or [math.nan]),
           100 * max(finite(all_err_mb) or [math.nan])),
        y=0.99 if ncols > 2 else 1.01,
        fontsize=11,
    )
    rp.save(fig, args.output, args.dpi)


def main(argv=None, name=NAME, doc=__doc__, title=None):
    args = rp.parse_args(doc, name, argv=argv)
    plot(args, title=title or name)


if __name__ == "__main__":
    rp.run(lambda: main(sys.argv[1:]))
