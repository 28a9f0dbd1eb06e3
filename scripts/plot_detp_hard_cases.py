#!/usr/bin/env python3
"""DETP's hard cases (experiment detp-hard-cases, docs/hard-cases.md): bias against s/d per case.

One panel per (scene, case) (points at distance s from an edge or contact line), one line per
detp.edge mode and one for the photon map (the same photons; it does not depend on the mode, so the
paper rows' values are used): the mean of (estimate − truth) over the case's points at that s,
± 95 % CI: DETP's across replicas (the irradiance_replica_K columns; a replica's points share its
photons, so per-point SEs cannot simply be summed), Student-t on Welch–Satterthwaite degrees of
freedom; the photon map's from the per-point SEs (the table keeps its pooled value only). The truth is the scene's closed form
(irradiance_exact) where it has one, else the reference engine's value (reference_e, whose SE is
added in quadrature). The bias is relative
to the case's mean truth at that s; where that is ~0 (a shadow, under a box) it is relative to the
mean truth over every point, and the panel says so. The case and s of each point come from the
points file (extra columns `case`, `s`), joined by row order (`sample`).

Prints a table: scene, case, s/d, and per mode the bias ± SE (relative to the mean truth, or in
W/m² where the truth is ~0), the SE as above.
"""

import math

import raycost_plot as rp
from raycost_stats import t95

NAME = "detp-hard-cases"
POINTS = "experiments/scenes/hard/hard-cases.points.csv"
MARKERS = {"paper": ("C3", "o"), "clamp-radius": ("C0", "s"), "first-hit": ("C2", "^"), "clamp-first-hit": ("C1", "D"),
           "photon map": ("0.5", "v")}


def extra(parser):
    parser.add_argument("--points-file", default=POINTS, metavar="CSV",
                        help="the points file the run read, with columns case and s (default: %(default)s)")


def finite(x):
    return isinstance(x, (int, float)) and x == x


def truth_of(r):
    """(truth, its SE)."""
    if finite(r["irradiance_exact"]):
        return r["irradiance_exact"], 0.0
    if finite(r.get("reference_e")):
        return r["reference_e"], r["reference_se"]
    raise rp.PlotError("point %s of sweep point %s has neither irradiance_exact nor reference_e"
                       % (r["sample"], r["point"]))


def base_radius(csv_path):
    """d of the run when it is not swept: the spec as recorded in NAME.meta.toml."""
    import tomllib

    meta = csv_path[:-4] + ".meta.toml" if csv_path.endswith(".csv") else csv_path + ".meta.toml"
    try:
        with open(meta, "rb") as f:
            return tomllib.load(f)["spec"]["base"]["detp"]["disc_radius"]
    except (OSError, KeyError) as e:
        raise rp.PlotError("%s: cannot read detp.disc_radius (%s)" % (meta, e))


def replica_values(r):
    """DETP's value at the point in each replica (irradiance_replica_K columns), [] if not written."""
    out = []
    while finite(r.get("irradiance_replica_%d" % len(out))):
        out.append(r["irradiance_replica_%d" % len(out)])
    return out


def group_error(g):
    """(mean error, SE, mean truth, degrees of freedom) of one group of points.

    g holds per point (error of the pooled estimate, its SE with the truth's, truth, the truth's SE,
    the errors in each replica or []). With ≥ 2 replicas the SE is taken across the replicas' mean
    errors over the group (the points of one replica share its photons, so their errors are
    correlated and a sum of per-point variances would understate it), plus the truth's own variance,
    with Welch–Satterthwaite degrees of freedom; otherwise the per-point variances are summed
    (normal quantile)."""
    n = len(g)
    mean = sum(x[0] for x in g) / n
    truth = sum(x[2] for x in g) / n
    reps = min(len(x[4]) for x in g)
    if reps >= 2:
        b = [sum(x[4][k] for x in g) / n for k in range(reps)]
        bm = sum(b) / reps
        a = sum((v - bm) ** 2 for v in b) / (reps - 1) / reps
        v_t = sum(x[3] ** 2 for x in g) / n ** 2
        denom = (a * a / (reps - 1) if a > 0 else 0.0) + (v_t * v_t / max(1, n - 1) if v_t > 0 else 0.0)
        dof = (a + v_t) ** 2 / denom if denom > 0 else math.nan
        return bm, math.sqrt(a + v_t), truth, dof
    return mean, math.sqrt(sum(x[1] ** 2 for x in g)) / n, truth, math.nan


def aggregate(main, side, labels):
    """{(mode, case, s/d): (mean error, SE, mean truth, degrees of freedom)} over the points of
    each group (group_error)."""
    d_of = {r["point"]: r["detp.disc_radius"] for r in main}
    groups = {}
    for r in side:
        case, s = labels[r["sample"]]
        scene = r.get("detp.scene", "scene").split("/")[-1]
        t, tse = truth_of(r)
        estimates = [(r["detp.edge"], r["irradiance_mean"], r["irradiance_se"], replica_values(r))]
        if r["detp.edge"] == "paper" and finite(r.get("photon_map_e")):
            # The points table keeps the photon map's pooled value only.
            estimates.append(("photon map", r["photon_map_e"], r["photon_map_se"], []))
        for mode, e, se, reps in estimates:
            key = (mode, scene, case, round(s / d_of[r["point"]], 6))
            groups.setdefault(key, []).append((e - t, math.sqrt(se ** 2 + tse ** 2), t, tse, [v - t for v in reps]))
    return {k: group_error(g) for k, g in groups.items()}


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
    modes = list(dict.fromkeys(k[0] for k in agg))
    scenes = list(dict.fromkeys(k[1] for k in agg))
    cases = list(dict.fromkeys(c for c, _ in labels))
    panels = [(sc, c) for sc in scenes for c in cases]
    ncols = 4
    nrows = (len(panels) + ncols - 1) // ncols
    fig, axes = rp.subplots(nrows, ncols, panel_w=4.4, panel_h=3.3)
    print("%-24s %-30s %5s  %s" % ("scene", "case", "s/d", "  ".join("%-22s" % m for m in modes)))
    for j, (scene, case) in enumerate(panels):
        ax = axes[j // ncols][j % ncols]
        sods = sorted({k[3] for k in agg if k[1] == scene and k[2] == case})
        overall = sum(v[2] for k, v in agg.items() if k[0] == modes[0] and k[1] == scene) / max(
            1, sum(1 for k in agg if k[0] == modes[0] and k[1] == scene))
        shadow = all(agg[(modes[0], scene, case, x)][2] < 0.02 * overall for x in sods)
        for m in modes:
            c, mk = MARKERS.get(m, ("C4", "D"))
            xs, ys, es = [], [], []
            for x in sods:
                if (m, scene, case, x) not in agg:
                    continue
                b, se, t, dof = agg[(m, scene, case, x)]
                ref = overall if shadow or t < 0.02 * overall else t
                xs.append(x)
                ys.append(b / ref)
                es.append(t95(dof) * se / ref)
            ax.errorbar(xs, ys, yerr=es, fmt=mk + "-", color=c, ms=4, capsize=2, label=m)
        for x in sods:
            cells = []
            for m in modes:
                b, se, t, _ = agg.get((m, scene, case, x), (float("nan"),) * 4)
                cells.append("%+6.1f%% ± %-5.1f%%" % (100 * b / t, 100 * se / t) if t > 0.02 * overall
                             else "%+7.3f ± %-6.3f W" % (b, se))
            print("%-24s %-30s %5.2f  %s" % (scene, case, x, "  ".join("%-22s" % c for c in cells)))
        ax.axhline(0, color="black", lw=0.8)
        ax.set_xscale("log")
        ax.set_xlabel("s / d")
        ax.set_ylabel("bias / mean truth over all points" if shadow else "relative bias")
        ax.set_title("%s: %s%s" % (scene.replace(".toml", ""), case, " (truth ≈ 0)" if shadow else ""),
                     fontsize=8)
        ax.legend(fontsize=7)
    for j in range(len(panels), nrows * ncols):
        axes[j // ncols][j % ncols].axis("off")
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME, extra=extra)
