#!/usr/bin/env python3
"""DETP's hard cases (experiment detp-hard-cases, docs/hard-cases.md): bias against s/d per case.

One panel per case (points at distance s from an edge or contact line), one line per detp.edge mode:
the mean of (estimate − truth) over the case's points at that s, ± 95 % CI (from the per-point
standard errors across replicas). The truth is the reference engine's value where NAME.points.csv
has one (column reference_e), else the scene's closed form (irradiance_exact). The bias is relative
to the case's mean truth at that s; where that is ~0 (a shadow, under a box) it is relative to the
mean truth over every point, and the panel says so. The case and s of each point come from the
points file (extra columns `case`, `s`), joined by row order (`sample`).

Prints a table: case, s/d, and per mode the bias ± SE.
"""

import math

import raycost_plot as rp

NAME = "detp-hard-cases"
POINTS = "experiments/scenes/hard/hard-cases.points.csv"
MARKERS = {"paper": ("C3", "o"), "clamp-radius": ("C0", "s"), "first-hit": ("C2", "^"), "clamp-first-hit": ("C1", "D")}


def extra(parser):
    parser.add_argument("--points-file", default=POINTS, metavar="CSV",
                        help="the points file the run read, with columns case and s (default: %(default)s)")


def truth_of(r):
    ref = r.get("reference_e")
    return ref if isinstance(ref, float) and ref == ref else r["irradiance_exact"]


def base_radius(csv_path):
    """d of the run when it is not swept: the spec as recorded in NAME.meta.toml."""
    import tomllib

    meta = csv_path[:-4] + ".meta.toml" if csv_path.endswith(".csv") else csv_path + ".meta.toml"
    try:
        with open(meta, "rb") as f:
            return tomllib.load(f)["spec"]["base"]["detp"]["disc_radius"]
    except (OSError, KeyError) as e:
        raise rp.PlotError("%s: cannot read detp.disc_radius (%s)" % (meta, e))


def aggregate(main, side, labels):
    """{(mode, case, s/d): (mean error, SE, mean truth)} over the points of each group."""
    d_of = {r["point"]: r["detp.disc_radius"] for r in main}
    groups = {}
    for r in side:
        case, s = labels[r["sample"]]
        key = (r["detp.edge"], case, round(s / d_of[r["point"]], 6))
        g = groups.setdefault(key, [])
        g.append((r["irradiance_mean"] - truth_of(r), r["irradiance_se"], truth_of(r)))
    out = {}
    for k, g in groups.items():
        n = len(g)
        out[k] = (sum(x[0] for x in g) / n, math.sqrt(sum(x[1] ** 2 for x in g)) / n, sum(x[2] for x in g) / n)
    return out


def plot(args):
    main, side = rp.with_params(args.input, "points", ["sample", "irradiance_mean", "irradiance_se",
                                                       "irradiance_exact"])
    if "detp.edge" not in main[0]:
        raise rp.PlotError("%s: no detp.edge column (sweep detp.edge)" % args.input)
    if "detp.disc_radius" not in main[0]:
        d = base_radius(args.input)
        for r in main:
            r["detp.disc_radius"] = d
    pts = rp.read_csv(args.points_file, ["case", "s"])
    labels = [(p["case"], p["s"]) for p in pts]
    if len(labels) < 1 + max(r["sample"] for r in side):
        raise rp.PlotError("%s has fewer points than %s: not the file of this run" % (args.points_file, args.input))
    agg = aggregate(main, side, labels)
    overall = sum(truth_of(r) for r in side) / len(side)
    modes = list(dict.fromkeys(k[0] for k in agg))
    cases = list(dict.fromkeys(c for c, _ in labels))
    ncols = 3
    nrows = (len(cases) + ncols - 1) // ncols
    fig, axes = rp.subplots(nrows, ncols, panel_w=4.6, panel_h=3.4)
    print("%-32s %5s  %s" % ("case", "s/d", "  ".join("%-24s" % m for m in modes)))
    for j, case in enumerate(cases):
        ax = axes[j // ncols][j % ncols]
        sods = sorted({k[2] for k in agg if k[1] == case})
        shadow = all(agg[(modes[0], case, x)][2] < 0.02 * overall for x in sods)
        for m in modes:
            c, mk = MARKERS.get(m, ("C4", "D"))
            xs, ys, es = [], [], []
            for x in sods:
                b, se, t = agg[(m, case, x)]
                ref = overall if shadow or t < 0.02 * overall else t
                xs.append(x)
                ys.append(b / ref)
                es.append(rp.Z95 * se / ref)
            ax.errorbar(xs, ys, yerr=es, fmt=mk + "-", color=c, ms=4, capsize=2, label=m)
        for x in sods:
            print("%-32s %5.2f  %s" % (case, x, "  ".join(
                "%+9.4f ± %-12.4f" % agg[(m, case, x)][:2] for m in modes)))
        ax.axhline(0, color="black", lw=0.8)
        ax.set_xscale("log")
        ax.set_xlabel("s / d")
        ax.set_ylabel("bias / mean truth over all points" if shadow else "relative bias")
        ax.set_title(case + (" (truth ≈ 0)" if shadow else ""), fontsize=9)
        ax.legend(fontsize=7)
    for j in range(len(cases), nrows * ncols):
        axes[j // ncols][j % ncols].axis("off")
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME, extra=extra)
