#!/usr/bin/env python3
"""f_R's control (experiment quasi-static-lines; the DETP paper's eq. 11, rule retraced-rays).

μ-random lines through the unit ball (r_0 = 1) and an absorbing sphere of radius r_D circling inside
it. Left: lines re-traced per frame — meeting the sphere at its old or its new pose (what
retraced_rays counts), and at the new pose only — mean ± 95 % CI over frames, against
f_R = n_R·(r_D/r_0)² (eq. 11, the count at one pose). Right: measured / f_R with the rule's band
[0.8, 1.25]; the old-or-new count is expected near 2 (two poses, little overlap), the new-pose count
at 1.
"""

import raycost_plot as rp

NAME = "quasi-static-lines"
REQUIRED = ["dynamic.ratio", "detp.engine", "retraced_rays_mean", "retraced_rays_se",
            "retraced_rays_theory", "rays_meeting_object_mean", "rays_meeting_object_se"]


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    fig, axes = rp.subplots(1, 2, panel_w=5.2, panel_h=4.2)
    ax_n, ax_q = axes[0]
    di = rp.sort_by([r for r in rows if r["detp.engine"] == "disc-index"], "dynamic.ratio")
    rp.measured(ax_n, di, "dynamic.ratio", "retraced_rays", label="old or new pose (mean ± 95 % CI)")
    rp.measured(ax_n, di, "dynamic.ratio", "rays_meeting_object", label="new pose", color="C2", marker="s")
    rp.theory(ax_n, di, "dynamic.ratio", "retraced_rays_theory", label="f_R = n_R·(r_D/r_0)² (eq. 11)")
    rp.log_scale(ax_n, x=True, y=True)
    ax_n.set_xlabel("r_D / r_0")
    ax_n.set_ylabel("lines re-traced per frame")
    ax_n.legend(fontsize=7)
    for stem, label, colour, marker in (("retraced_rays", "old or new pose", "C0", "o"),
                                        ("rays_meeting_object", "new pose", "C2", "s")):
        xs = rp.col(di, "dynamic.ratio")
        q = [r[stem + "_mean"] / r["retraced_rays_theory"] for r in di]
        e = [1.96 * r[stem + "_se"] / r["retraced_rays_theory"] for r in di]
        ax_q.errorbar(xs, q, yerr=e, fmt=marker + "-", color=colour, ms=4, capsize=3,
                      label=label + " / f_R (± 95 % CI)")
        for r, v in zip(di, q):
            print("r_D/r_0 %.2f: %s %.0f ± %.0f vs f_R %.0f: ratio %.4f" % (
                r["dynamic.ratio"], label, r[stem + "_mean"], r[stem + "_se"], r["retraced_rays_theory"], v))
    ax_q.axhspan(0.8, 1.25, color="0.9", label="rule band [0.8, 1.25]")
    ax_q.axhline(1.0, color="k", lw=0.8)
    rp.log_scale(ax_q, x=True)
    ax_q.set_xlabel("r_D / r_0")
    ax_q.set_ylabel("measured / f_R")
    ax_q.legend(fontsize=7)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
