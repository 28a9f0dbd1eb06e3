#!/usr/bin/env python3
"""Speed against error (experiment detp-accuracy): one panel per scene with exact irradiance.

Every method's relative RMSE (RMSE over the mean exact irradiance, mean ± 95 % CI across replicas)
against its wall time (photon tracing + the engine): DETP through the sphere cache and through the
disc index (same estimate, bit for bit; different time), and the photon map. Marker size grows with
the photon count; labels give d (DETP) or k (photon map). The front of best choices (no faster method
is as accurate) is drawn as a step line. A second row shows the relative bias.
"""

import raycost_plot as rp

NAME = "detp-accuracy"
REQUIRED = ["detp.scene", "detp.photons", "detp.disc_radius", "detp.photon_map_k", "trace_s",
            "irradiance_theory", "irradiance_rmse_mean", "irradiance_rmse_se", "irradiance_bias_mean",
            "photon_map_rmse_mean", "photon_map_rmse_se", "photon_map_bias_mean",
            "cost_sphere_cache_s", "cost_disc_index_s", "cost_photon_map_s"]
METHODS = (
    ("DETP, sphere cache", "cost_sphere_cache_s", "irradiance", "detp.disc_radius", "d", "C0", "o"),
    ("DETP, disc index", "cost_disc_index_s", "irradiance", "detp.disc_radius", "d", "C2", "s"),
    ("photon map", "cost_photon_map_s", "photon_map", "detp.photon_map_k", "k", "C3", "^"),
)


def points_of(rows, cost, metric, key):
    """One point per (photons, key): DETP does not depend on k, the photon map not on d, so rows
    that differ only in the other key are the same estimate; their times are averaged."""
    out = {}
    for r in rows:
        k = (r["detp.photons"], r[key])
        e = out.setdefault(k, {"t": [], "rmse": r[metric + "_rmse_mean"], "ci": rp.ci95(r, metric + "_rmse"),
                               "bias": r[metric + "_bias_mean"], "exact": r["irradiance_theory"],
                               "photons": r["detp.photons"], "label": r[key]})
        e["t"].append(r["trace_s"] + r[cost])
    return [dict(v, t=sum(v["t"]) / len(v["t"])) for v in out.values()]


def front(pts):
    best, line = float("inf"), []
    for p in sorted(pts, key=lambda p: p["t"]):
        if p["rmse"] < best:
            best = p["rmse"]
            line.append(p)
    return line


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    scenes = list(dict.fromkeys(r["detp.scene"] for r in rows))
    fig, axes = rp.subplots(2, len(scenes), panel_w=6.2, panel_h=4.2)
    for j, scene in enumerate(scenes):
        sub = [r for r in rows if r["detp.scene"] == scene]
        ax, ax_b = axes[0][j], axes[1][j]
        every = []
        for label, cost, metric, key, short, color, marker in METHODS:
            pts = points_of(sub, cost, metric, key)
            for p in pts:
                rel = p["rmse"] / p["exact"]
                ax.errorbar([p["t"]], [rel], yerr=[p["ci"] / p["exact"]], fmt=marker, color=color,
                            ms=3 + 2 * (len(str(int(p["photons"]))) - 4), capsize=2, alpha=0.85)
                ax.annotate("%s=%g" % (short, p["label"]), (p["t"], rel), fontsize=6, xytext=(3, 2),
                            textcoords="offset points")
                ax_b.plot([p["t"]], [p["bias"] / p["exact"]], marker, color=color, ms=4)
            ax.plot([], [], marker, color=color, label=label)
            every.extend(dict(p, method=label) for p in pts)
        f = front(every)
        ax.step([p["t"] for p in f], [p["rmse"] / p["exact"] for p in f], where="post", color="black",
                lw=1, label="front of best choices")
        for a in (ax, ax_b):
            a.set_xscale("log")
            a.set_xlabel("wall time: photon tracing + engine, s")
        ax.set_yscale("log")
        ax.set_ylabel("relative RMSE")
        ax.set_title(scene.split("/")[-1], fontsize=10)
        ax.legend(fontsize=7)
        ax_b.axhline(0, color="black", lw=0.8)
        ax_b.set_ylabel("relative bias")
        print("%s: front of best choices: %s" % (scene, "; ".join(
            "%s %s=%g, %d photons, %.3g s, rel. RMSE %.3g" % (p["method"], "k" if "photon" in p["method"] else "d",
                                                             p["label"], p["photons"], p["t"], p["rmse"] / p["exact"])
            for p in f)))
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
