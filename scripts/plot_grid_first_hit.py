#!/usr/bin/env python3
"""The laws behind Result 3.1, measured vs theory (experiment grid-first-hit).

One row per sweep point. Left: histogram of the first-hit distance t* (bars, log y) with the counts an
Exponential(ρπr²) law predicts (line), annotated with the KS statistic and p (t_hit_ks, t_hit_ks_p) and
χ²/dof and p (t_hit_chi2, t_hit_chi2_p). Right: histogram of N_I with mailboxing (distinct spheres
tested) against the fitted geometric law, annotated with n_i_mb_chi2 and its p.
The last bin of each histogram is the overflow (bin_hi = inf), drawn hatched.
Reads NAME.hist.csv (columns point, metric, bin_lo, bin_hi, count, expected) beside the main CSV.
"""

import math

import raycost_plot as rp

NAME = "grid-first-hit"
MAIN_REQUIRED = ["point", "t_hit_ks_p", "t_hit_chi2_p", "n_i_mb_chi2_p"]
HIST_REQUIRED = ["point", "metric", "bin_lo", "bin_hi", "count", "expected"]
GROUP_KEYS = ("grid.cell_width", "scene.radius", "scene.intensity", "grid.eye")


def extra(parser):
    parser.add_argument(
        "--hist",
        default=None,
        metavar="CSV",
        help="histogram table (default: NAME.hist.csv beside --input)",
    )


def rebin(bins, max_bins=90):
    """Merge runs of k consecutive regular bins (sum of counts and expected) so that at most about
    max_bins are drawn; the overflow bin stays as is. Returns (bins, k)."""
    regular = [b for b in bins if b["bin_hi"] != math.inf]
    over = [b for b in bins if b["bin_hi"] == math.inf]
    k = math.ceil(len(regular) / max_bins)
    if k <= 1:
        return bins, 1
    merged = []
    for i in range(0, len(regular), k):
        run = regular[i:i + k]
        merged.append({
            "bin_lo": run[0]["bin_lo"],
            "bin_hi": run[-1]["bin_hi"],
            "count": sum(b["count"] for b in run),
            "expected": sum(b["expected"] for b in run),
        })
    return merged + over, k


def draw_hist(ax, bins, label, xlabel):
    """Measured counts as filled stairs, expected counts as a line; overflow bin hatched."""
    bins, k = rebin(sorted(bins, key=lambda b: b["bin_lo"]))
    if k > 1:
        xlabel += "  (shown in bins of %d)" % k
    edges = [b["bin_lo"] for b in bins]
    last = bins[-1]
    overflow = last["bin_hi"] == math.inf
    width = (bins[-2]["bin_hi"] - bins[-2]["bin_lo"]) if len(bins) > 1 else 1.0
    edges.append(last["bin_lo"] + width if overflow else last["bin_hi"])
    counts = [b["count"] for b in bins]
    expected = [b["expected"] for b in bins]
    base = 0.5
    ax.stairs(counts, edges, fill=True, baseline=base, color="C0", alpha=0.55,
              label="measured counts")
    ax.stairs(expected, edges, baseline=None, color="black", lw=1.3, label=label)
    if overflow:
        ax.bar(edges[-2], max(counts[-1], base), width=edges[-1] - edges[-2], bottom=0 if counts[-1] else base,
               align="edge", fill=False, hatch="///", ec="C0", lw=0.8,
               label="overflow (≥ %.4g): %d vs %.1f expected" % (last["bin_lo"], counts[-1], expected[-1]))
    ax.set_yscale("log")
    top = max(max(counts), max(e for e in expected if e == e))
    ax.set_ylim(base, top * 4)
    ax.set_xlim(edges[0], edges[-1])
    ax.set_xlabel(xlabel)
    ax.set_ylabel("rays per bin")
    ax.grid(True, alpha=0.3)


def p_text(name, stat, p, dof=None):
    flag = "  ← p < 0.01" if p == p and p < 0.01 else ""
    if dof is not None:
        return "%s = %.1f / %d dof, p = %.3g%s" % (name, stat, dof, p, flag)
    return "%s = %.4f, p = %.3g%s" % (name, stat, p, flag)


def plot(args):
    rows = rp.read_csv(args.input, MAIN_REQUIRED)
    hist_path = args.hist or rp.sibling_csv(args.input, "hist")
    hist = rp.read_csv(hist_path, HIST_REQUIRED)
    keys = [k for k in GROUP_KEYS if rp.has(rows, k)]

    fig, axes = rp.subplots(len(rows), 2, panel_w=6.0, panel_h=3.6)
    for i, row in enumerate(rows):
        p = row["point"]
        head = "point %d: %s" % (p, rp.group_label(keys, [row[k] for k in keys])) if keys else "point %d" % p
        ax_t, ax_n = axes[i]

        t_bins = [b for b in hist if b["point"] == p and b["metric"] == "t_hit"]
        if t_bins:
            draw_hist(ax_t, t_bins, "expected: Exponential(ρπr²)", "first-hit distance t*")
            lines = [
                "mean t*: %.3g ± %.2g (theory %.3g)"
                % (row.get("t_hit_mean", math.nan), rp.ci95(row, "t_hit"), row.get("t_hit_theory", math.nan)),
                p_text("KS D", row.get("t_hit_ks", math.nan), row["t_hit_ks_p"]),
                p_text("χ²", row.get("t_hit_chi2", math.nan), row["t_hit_chi2_p"], row.get("t_hit_chi2_dof")),
            ]
            rp.text_box(ax_t, "\n".join(lines), loc="lower left", fontsize=7.5)
            ax_t.legend(fontsize=7.5, loc="upper right")
        else:
            ax_t.text(0.5, 0.5, "no t_hit histogram", ha="center", transform=ax_t.transAxes)
        ax_t.set_title(head + " — t*", fontsize=9.5)

        n_bins = [b for b in hist if b["point"] == p and b["metric"] == "n_i_mb"]
        if n_bins:
            geo = row.get("n_i_geometric_p")
            draw_hist(ax_n, n_bins,
                      "fitted geometric" + (" (p = %.3g)" % geo if isinstance(geo, float) else ""),
                      "N_I with mailboxing (distinct spheres tested)")
            lines = [
                "mean N_I: %.3g ± %.2g (n_i_mb_theory %.3g)"
                % (row.get("n_i_mb_mean", math.nan), rp.ci95(row, "n_i_mb"), row.get("n_i_mb_theory", math.nan)),
                p_text("χ²", row.get("n_i_mb_chi2", math.nan), row["n_i_mb_chi2_p"], row.get("n_i_mb_chi2_dof")),
            ]
            if isinstance(row.get("n_i_cylinder_radius"), float):
                lines.append("cylinder radius s of the fit: %.3g" % row["n_i_cylinder_radius"])
            rp.text_box(ax_n, "\n".join(lines), loc="lower left", fontsize=7.5)
            ax_n.legend(fontsize=7.5, loc="upper right")
        else:
            ax_n.text(0.5, 0.5, "no n_i_mb histogram", ha="center", transform=ax_n.transAxes)
        ax_n.set_title(head + " — N_I (mailbox)", fontsize=9.5)

    fig.suptitle("%s: t* ~ Exponential(ρπr²) (eq. 4) and N_I ~ geometric (cylinder model, eq. 9)"
                 % NAME, fontsize=11, y=1.0)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME, extra=extra)
