#!/usr/bin/env python3
"""Speed against error on the BART kitchen (experiment speed-vs-error): seconds per frame against
the irradiance error of the last frame (relative RMSE over the points against a high-photon
reference), one curve per engine over the photon counts, and the full recalculation (same error,
its own time). Lower-left is better.
"""

import raycost_plot as rp

NAME = "speed-vs-error"
REQUIRED = ["detp.photons", "detp.engine", "frame_s_mean", "full_frame_s_mean", "irradiance_rmse"]


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    fig, axes = rp.subplots(1, 1, panel_w=6.0, panel_h=4.5)
    ax = axes[0][0]
    for i, eng in enumerate(("hybrid", "sphere-cache", "disc-index")):
        rs = rp.sort_by([r for r in rows if r["detp.engine"] == eng], "detp.photons")
        ax.plot(rp.col(rs, "frame_s_mean"), rp.col(rs, "irradiance_rmse"), "o-", color="C%d" % i, label="incremental, %s" % eng)
        for r in rs:
            print("%-12s %8d photons: frame %.4f s, full %.3f s, relative RMSE %.4f" % (
                eng, r["detp.photons"], r["frame_s_mean"], r["full_frame_s_mean"], r["irradiance_rmse"]))
    full = rp.sort_by([r for r in rows if r["detp.engine"] == "hybrid"], "detp.photons")
    ax.plot(rp.col(full, "full_frame_s_mean"), rp.col(full, "irradiance_rmse"), "s--", color="0.3", label="full recalculation")
    for r in full:
        ax.annotate("%dk" % (r["detp.photons"] // 1000), (r["full_frame_s_mean"], r["irradiance_rmse"]), fontsize=7,
                    xytext=(4, 4), textcoords="offset points")
    rp.log_scale(ax, x=True, y=True)
    ax.set_xlabel("seconds per frame")
    ax.set_ylabel("irradiance error (relative RMSE vs reference)")
    ax.legend(fontsize=7)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
