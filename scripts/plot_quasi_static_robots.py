#!/usr/bin/env python3
"""Many dynamic objects (experiment quasi-static-robots: BART's ten walking robots). Left: seconds
per frame, incremental (every frame) and full recalculation (checked frames). Right: rays re-traced
per frame (old or new pose, and new pose only) against f_R = n_R·Σ(r_D/r_0)² over the robots.
"""

import raycost_plot as rp

NAME = "quasi-static-robots"


def plot(args):
    rows, frames = rp.with_params(args.input, "frames", ["frame", "frame_s", "full_frame_s", "retraced_rays",
                                                         "rays_meeting_object"])
    r = rows[0]
    f = [x for x in frames if x["frame"] > 0]
    fig, axes = rp.subplots(1, 2, panel_w=5.6, panel_h=4.2)
    ax_t, ax_r = axes[0]
    ax_t.plot(rp.col(f, "frame"), rp.col(f, "frame_s"), "o-", ms=3, label="incremental")
    full = [x for x in f if x["full_frame_s"] == x["full_frame_s"]]
    ax_t.plot(rp.col(full, "frame"), rp.col(full, "full_frame_s"), "s", color="C3", label="full recalculation")
    rp.log_scale(ax_t, y=True)
    ax_t.set_xlabel("frame")
    ax_t.set_ylabel("seconds per frame")
    ax_t.legend(fontsize=7)
    ax_r.plot(rp.col(f, "frame"), rp.col(f, "retraced_rays"), "o-", ms=3, label="old or new pose")
    ax_r.plot(rp.col(f, "frame"), rp.col(f, "rays_meeting_object"), "s-", ms=3, label="new pose")
    ax_r.axhline(r["retraced_rays_theory"], color="0.3", ls="--", label="f_R = n_R·Σ(r_D/r_0)²")
    ax_r.set_xlabel("frame")
    ax_r.set_ylabel("rays re-traced per frame")
    ax_r.legend(fontsize=7)
    print("%d objects, %d static + %d dynamic points, %d segments: frame %.4f s vs full %.3f s (%.1f×); re-traced %.1f (new pose %.1f) vs f_R %.1f; %d mismatches in %d checked frames; %d warnings" % (
        r["objects"], r["points_static"], r["points_dynamic"], r["segments"], r["frame_s_mean"], r["full_frame_s_mean"],
        r["full_frame_s_mean"] / r["frame_s_mean"], r["retraced_rays_mean"], r["rays_meeting_object_mean"],
        r["retraced_rays_theory"], r["full_mismatch"], r["full_checked"], r["warnings"]))
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
