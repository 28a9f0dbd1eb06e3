#!/usr/bin/env python3
"""Speed against error on a real scene against the path-traced reference (experiments speed-vs-error,
the BART kitchen, and speed-vs-error-cornell, the Cornell box; engine "reference").

Left: RMSE against the true irradiance (estimated against the reference, its own variance
subtracted), relative to the mean reference irradiance, against seconds (photon tracing + the
engine), ± 95 % CI: DETP with the sphere cache and with the disc index (one curve per disc radius d,
over photon counts; both engines give the same estimate, so they differ in time only) and the photon
map (one curve per k). The grey steps are the front of best choices: configurations no other is both
faster and more accurate than. Right: the relative bias (mean error over the points) ± 95 % CI.
One row of panels per scene (detp.scene), DETP curves per d and edge mode (detp.edge): rows of
different scenes or edge modes are never averaged together.
"""

import raycost_plot as rp
from raycost_stats import dof, t95

NAME = "speed-vs-error"
REQUIRED = ["detp.photons", "detp.disc_radius", "detp.photon_map_k", "trace_s", "cost_sphere_cache_s",
            "cost_disc_index_s", "cost_photon_map_s", "reference_irradiance_mean",
            "irradiance_ref_rmse_mean", "irradiance_ref_rmse_se", "irradiance_ref_bias_mean",
            "irradiance_ref_bias_se", "photon_map_ref_rmse_mean", "photon_map_ref_rmse_se",
            "photon_map_ref_bias_mean", "photon_map_ref_bias_se"]


def configurations(rows):
    """One entry per (method, setting, photons): seconds, relative RMSE and the half-width of its
    95 % CI, relative bias and its 95 % CI half-width. DETP rows at the same photons and d (but other
    k) are independent runs: averaged, their SEs combined and their degrees of freedom added (each
    row's M_clusters − 1), the CI Student-t on that sum."""
    out = {}
    for r in rows:
        ref = r["reference_irradiance_mean"]
        detp = "d = %g" % r["detp.disc_radius"] + (", %s" % r["detp.edge"] if "detp.edge" in r else "")
        for method, cost, stem, setting in (
                ("DETP sphere cache", "cost_sphere_cache_s", "irradiance_ref", detp),
                ("DETP disc index", "cost_disc_index_s", "irradiance_ref", detp),
                ("photon map", "cost_photon_map_s", "photon_map_ref", "k = %d" % r["detp.photon_map_k"])):
            key = (method, setting, r["detp.photons"])
            # Since issue 27 a photon map's cost_{}_s is its queries and build_{}_s its kd-tree:
            # both are paid (tables from before have the build inside cost_{}_s and no build column).
            build = r.get(cost.replace("cost_", "build_"), 0.0) if method == "photon map" else 0.0
            seconds = r["trace_s"] + r[cost] + (build if build == build else 0.0)
            out.setdefault(key, []).append((seconds, r[stem + "_rmse_mean"] / ref,
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
    fig, axes = rp.subplots(len(scenes), 2, panel_w=6.0, panel_h=4.6)
    for row, scene in enumerate(scenes):
        mine = [r for r in rows if scene is None or r["detp.scene"] == scene]
        if scene is not None:
            print("== %s" % scene)
        panels(axes[row], configurations(mine), scene)
    rp.finish(fig, args)


def panels(axes, conf, scene):
    """One scene's RMSE-vs-seconds panel (with its front) and bias panel."""
    ax_r, ax_b = axes
    series = sorted({(m, s) for m, s, _ in conf})
    styles = {"DETP sphere cache": "o-", "DETP disc index": "s--", "photon map": "^:"}
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
        print("front: %-18s %-24s %9d photons: %8.3f s, relative RMSE %.4f" % (m, s, p, t, e))
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
