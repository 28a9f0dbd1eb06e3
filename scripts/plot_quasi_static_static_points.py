#!/usr/bin/env python3
"""Static points updated per frame by the disc index vs the sphere cache (experiment
quasi-static-static-points; the DETP paper's eqs. 13–14: 2·t·f_R·∛n_S vs 8.08·t·f_R·∛n_S).

Left: counted tests per frame of each engine against its closed form, over f_R·∛n_S. Right: the
measured sphere-cache / disc-index ratio of tests and of seconds, against the paper's 8.08/2 = 4.04.
"""

import raycost_plot as rp

NAME = "quasi-static-static-points"
REQUIRED = ["dynamic.ratio", "detp.engine", "detp.point_spacing", "static_tests_mean", "static_s_mean",
            "static_tests_theory_sphere_cache", "static_tests_theory_disc_index", "retraced_rays_theory",
            "points_static"]


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    fig, axes = rp.subplots(1, 2, panel_w=5.8, panel_h=4.3)
    ax, ax_r = axes[0]
    for eng, c, th in (("disc-index", "C1", "static_tests_theory_disc_index"),
                       ("sphere-cache", "C0", "static_tests_theory_sphere_cache")):
        rs = [r for r in rows if r["detp.engine"] == eng]
        x = [r["retraced_rays_theory"] * r["points_static"] ** (1 / 3) for r in rs]
        ax.plot(x, rp.col(rs, "static_tests_mean"), "o", color=c, label="%s, counted" % eng)
        order = sorted(range(len(x)), key=lambda i: x[i])
        ax.plot([x[i] for i in order], [rs[i][th] for i in order], "-", color=c, label="%s, eq. %s" % (eng, "14" if eng == "disc-index" else "13"))
    rp.log_scale(ax, x=True, y=True)
    ax.set_xlabel("f_R·∛n_S")
    ax.set_ylabel("tests per frame, static points")
    ax.legend(fontsize=7)
    di = {(r["dynamic.ratio"], r["detp.point_spacing"]): r for r in rows if r["detp.engine"] == "disc-index"}
    pts, rt, rs_ = [], [], []
    for r in rows:
        if r["detp.engine"] != "sphere-cache":
            continue
        d = di.get((r["dynamic.ratio"], r["detp.point_spacing"]))
        if not d:
            continue
        pts.append(r["points_static"])
        rt.append(r["static_tests_mean"] / d["static_tests_mean"])
        rs_.append(r["static_s_mean"] / d["static_s_mean"])
        print("r_D/r_0 %.2f, n_S %6d: tests sphere cache / disc index = %.2f, seconds %.2f (paper 4.04)" % (
            r["dynamic.ratio"], r["points_static"], rt[-1], rs_[-1]))
    ax_r.plot(pts, rt, "o", color="C2", label="tests ratio")
    ax_r.plot(pts, rs_, "s", color="C4", label="seconds ratio")
    ax_r.axhline(8.08 / 2, color="0.3", ls="--", label="paper: 8.08 / 2 = 4.04")
    rp.log_scale(ax_r, x=True, y=True)
    ax_r.set_xlabel("static points n_S")
    ax_r.set_ylabel("sphere cache / disc index, per frame")
    ax_r.legend(fontsize=7)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
