#!/usr/bin/env python3
"""Speed against error on a real scene against the path-traced reference (experiments speed-vs-error,
the BART kitchen, and speed-vs-error-cornell, the Cornell box; engine "reference").

Left: RMSE against the true irradiance (estimated against the reference, its own variance
subtracted), relative to the mean reference irradiance, against seconds (photon tracing + the
engine), ± 95 % CI: DETP with the sphere cache and with the disc index (one curve per disc radius d,
over photon counts; both engines give the same estimate, so they differ in time only) and the photon
map (one curve per k; with engine photon-map-growing's columns also the photon map whose k grows
with the photon count), and per-point path tracing over its paths per point K (side table
NAME.path_tracing.csv, written by the fronts: experiments fronts-*). Seconds are everything an estimate pays: photon
tracing, the edge remedy, NEE direct light, the build and the engine. The grey steps are the front of best choices: configurations no other is both
faster and more accurate than. Right: the relative bias (mean error over the points) ± 95 % CI.
One row of panels per scene (detp.scene), DETP curves per d and edge mode (detp.edge): rows of
different scenes or edge modes are never averaged together.
"""

import math
import os

import raycost_plot as rp
from raycost_stats import dof, t95

NAME = "speed-vs-error"
REQUIRED = ["detp.photons", "detp.disc_radius", "detp.photon_map_k", "trace_s", "cost_sphere_cache_s",
            "cost_disc_index_s", "cost_photon_map_s", "reference_irradiance_mean",
            "irradiance_ref_rmse_mean", "irradiance_ref_rmse_se", "irradiance_ref_bias_mean",
            "irradiance_ref_bias_se", "photon_map_ref_rmse_mean", "photon_map_ref_rmse_se",
            "photon_map_ref_bias_mean", "photon_map_ref_bias_se"]


def seconds_of(r, cost):
    """Everything one estimate pays, summed over its replicas: photon tracing, the edge remedy, NEE
    direct light (detp.direct = "nee"), the engine's once-per-photon-set build and its work on the
    points. Columns a table from before lacks count 0 (the photon map's kd-tree was inside its
    cost_{}_s before build_{}_s existed)."""
    total = r["trace_s"] + r[cost]
    for extra in ("edge_s", "direct_s", cost.replace("cost_", "build_")):
        v = r.get(extra, 0.0)
        total += v if v == v else 0.0
    return total


def methods(r):
    """(method, cost column, error stem, setting) for each estimator a row measured."""
    detp = "d = %g" % r["detp.disc_radius"] + (", %s" % r["detp.edge"] if "detp.edge" in r else "")
    if r.get("detp.direct") == "nee":
        detp += ", NEE direct"
    nee = ", NEE direct" if r.get("detp.direct") == "nee" else ""
    out = [("DETP sphere cache", "cost_sphere_cache_s", "irradiance_ref", detp),
           ("DETP disc index", "cost_disc_index_s", "irradiance_ref", detp),
           ("photon map", "cost_photon_map_s", "photon_map_ref", "k = %d" % r["detp.photon_map_k"] + nee)]
    if r.get("photon_map_growing_ref_rmse_mean") is not None:
        # One curve over N: its k (photon_map_growing_k) changes with N by design.
        out.append(("photon map, growing k", "cost_photon_map_growing_s", "photon_map_growing_ref",
                    "k = %g at %g photons, ∝ N^%g" % (r["detp.photon_map_k"], r["detp.photon_map_k_photons"],
                                                      r["detp.photon_map_k_growth"]) + nee))
    return [m for m in out if r.get(m[2] + "_rmse_mean") == r.get(m[2] + "_rmse_mean")]


def configurations(rows):
    """One entry per (method, setting, photons): seconds, relative RMSE and the half-width of its
    95 % CI, relative bias and its 95 % CI half-width. DETP rows at the same photons and d (but other
    k) are independent runs: averaged, their SEs combined and their degrees of freedom added (each
    row's M_clusters − 1), the CI Student-t on that sum."""
    out = {}
    for r in rows:
        ref = r["reference_irradiance_mean"]
        for method, cost, stem, setting in methods(r):
            key = (method, setting, r["detp.photons"])
            out.setdefault(key, []).append((seconds_of(r, cost), r[stem + "_rmse_mean"] / ref,
                                             r[stem + "_rmse_se"] / ref, r[stem + "_bias_mean"] / ref,
                                             r[stem + "_bias_se"] / ref, dof(r, stem + "_rmse"),
                                             dof(r, stem + "_bias")))
    avg = {}
    for key, vs in out.items():
        n = len(vs)
        m = [sum(v[i] for v in vs) / n for i in range(5)]
        # SE of a mean of n independent runs: √(Σ SE²)/n.
        se_r = (sum(v[2] ** 2 for v in vs)) ** 0.5 / n
        se_b = (sum(v[4] ** 2 for v in vs)) ** 0.5 / n
        avg[key] = (m[0], m[1], t95(sum(v[5] for v in vs)) * se_r, m[3], t95(sum(v[6] for v in vs)) * se_b)
    return avg


def path_tracing(csv_path, rows):
    """Per-point path tracing (engine "path-tracing", side table NAME.path_tracing.csv) as a curve
    over its checkpoints K = 1, 2, 4, …: keyed like `configurations` with K in place of photons.
    Seconds are one replica's (each replica is one estimate of K paths per point); the relative MSE
    is the mean over replicas of each replica's MSE against the reference (its variance subtracted),
    its 95 % CI Student-t across replicas, carried to the RMSE by the delta method. The run traces
    the same paths at every sweep point of one point set, so one sweep point per scene is read."""
    path = rp.sibling_csv(csv_path, "path_tracing")
    if not os.path.exists(path):
        return {}
    side = rp.read_csv(path, ["point", "replica", "paths", "seconds_s", "ref_mse", "ref_bias"])
    by_point = {int(r["point"]): r for r in rows}
    seen, out = {}, {}
    for s in side:
        main = by_point.get(int(s["point"]))
        if main is None or s["ref_mse"] != s["ref_mse"]:
            continue
        scene = main.get("detp.scene")
        first = seen.setdefault(scene, int(s["point"]))
        if first != int(s["point"]):
            continue
        out.setdefault((scene, s["paths"]), []).append((s, main["reference_irradiance_mean"]))
    conf = {}
    for (scene, k), vs in out.items():
        n = len(vs)
        ref = vs[0][1]
        mse = [v[0]["ref_mse"] / ref ** 2 for v in vs]
        bias = [v[0]["ref_bias"] / ref for v in vs]
        mean_mse = sum(mse) / n
        rmse = max(mean_mse, 0.0) ** 0.5
        half = lambda xs: t95(n - 1) * (sum((x - sum(xs) / n) ** 2 for x in xs) / (n - 1) / n) ** 0.5 \
            if n > 1 else math.nan
        rmse_half = half(mse) / (2 * rmse) if rmse > 0 else math.nan
        seconds = sum(v[0]["seconds_s"] for v in vs) / n
        conf[(scene, ("path tracing", "NEE, paths per point", k))] = (
            seconds, rmse, rmse_half, sum(bias) / n, half(bias))
    return conf


def front(points):
    """The (seconds, error) points no other point beats on both."""
    best, out = float("inf"), []
    for t, e in sorted(points):
        if e < best:
            out.append((t, e))
            best = e
    return out


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    scenes = sorted({r["detp.scene"] for r in rows}) if rp.has(rows, "detp.scene") else [None]
    pt = path_tracing(args.input, rows)
    fig, axes = rp.subplots(len(scenes), 2, panel_w=6.0, panel_h=4.6)
    for row, scene in enumerate(scenes):
        mine = [r for r in rows if scene is None or r["detp.scene"] == scene]
        if scene is not None:
            print("== %s" % scene)
        conf = configurations(mine)
        conf.update({k: v for (sc, k), v in pt.items() if sc == scene})
        panels(axes[row], conf, scene)
    rp.finish(fig, args)


def panels(axes, conf, scene):
    """One scene's RMSE-vs-seconds panel (with its front) and bias panel."""
    ax_r, ax_b = axes
    series = sorted({(m, s) for m, s, _ in conf})
    styles = {"DETP sphere cache": "o-", "DETP disc index": "s--", "photon map": "^:",
              "photon map, growing k": "v:", "path tracing": "D-."}
    for i, (m, s) in enumerate(series):
        pts = sorted((p, conf[(m, s, p)]) for mm, ss, p in conf if (mm, ss) == (m, s))
        t = [v[0] for _, v in pts]
        c = "C%d" % (i % 10)
        for ax, y, e in ((ax_r, 1, 2), (ax_b, 3, 4)):
            ax.errorbar(t, [v[y] for _, v in pts], yerr=[v[e] for _, v in pts], fmt=styles[m], color=c,
                        ms=4, capsize=2, label="%s, %s" % (m, s))
        for p, v in pts:
            print("%-18s %-24s %9d photons: %8.3f s, relative RMSE %.4f ± %.4f, relative bias %+.4f ± %.4f"
                  % (m, s, p, v[0], v[1], v[2], v[3], v[4]))
    best = front([(v[0], v[1]) for v in conf.values()])
    ax_r.step([b[0] for b in best], [b[1] for b in best], where="post", color="0.5", lw=3, alpha=0.35,
              label="front of best choices", zorder=0)
    names = {(round(v[0], 9), round(v[1], 12)): k for k, v in conf.items()}
    for t, e in best:
        m, s, p = names[(round(t, 9), round(e, 12))]
        print("front: %-18s %-24s %9d photons/paths: %8.3f s, relative RMSE %.4f" % (m, s, p, t, e))
    rp.log_scale(ax_r, x=True, y=True)
    title = "" if scene is None else scene.split("/")[-1] + ": "
    ax_r.set_title(title + "error against seconds", fontsize=9)
    ax_r.set_xlabel("seconds (photon tracing + engine)")
    ax_r.set_ylabel("relative RMSE vs truth (reference variance removed)")
    ax_r.legend(fontsize=5)
    ax_b.axhline(0.0, color="0.5", lw=0.8)
    rp.log_scale(ax_b, x=True)
    ax_b.set_title(title + "bias", fontsize=9)
    ax_b.set_xlabel("seconds (photon tracing + engine)")
    ax_b.set_ylabel("relative bias vs reference (mean error / mean E)")


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
