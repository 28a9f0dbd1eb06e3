#!/usr/bin/env python3
"""Rays per sphere-cache level in a real scene against the uniform-line law (experiment cornell-levels;
the paper's Figures 6–7 for its real scenes). One series per swept combination (scene, list mode).
Left: rays held by a level-i sphere (mean ± 95 % CI across replicas, log y), the law n_R·(r_i/r_0)² with
n_R the stored segments, and the §4.1 calibrated law: the law scaled by Σ measured / Σ law over the
upper levels (--calibrate, default levels 1–4), as the paper's predictor traces the upper levels and
extrapolates. Right: the error of the raw law (solid) and of the calibrated law (dashed) per level,
**relative to the measurement**: (law − measured) / measured, with the paper's ±5 %.
"""
import raycost_plot as rp

NAME = "cornell-levels"
REQUIRED = ["level", "radius", "rays_level_mean", "rays_level_se", "rays_level_theory"]


def extra(p):
    p.add_argument("--calibrate", default="1-4",
                   help="levels the §4.1 calibration uses, FIRST-LAST (default: %(default)s)")


def series_label(value, keys):
    parts = []
    for k, v in zip(keys, value):
        v = str(v)
        parts.append(v.split("/")[-1] if k == "detp.scene" else "%s lists" % v if k == "detp.list_mode" else v)
    return ", ".join(parts) or "as run"


def plot(args):
    first, last = (int(x) for x in args.calibrate.split("-"))
    main, levels = rp.with_params(args.input, "levels", REQUIRED)
    keys = [k for k in ("detp.scene", "detp.list_mode") if rp.has(levels, k)]
    groups = rp.group_by(levels, *keys)[1] if keys else {(): levels}
    fig, axes = rp.subplots(1, 2, panel_w=6.5, panel_h=4.6)
    ax, ax_e = axes[0]
    for j, (value, grp) in enumerate(groups.items()):
        grp = [r for r in rp.sort_by(grp, "level") if (r.get("rays_level_n") or 0) > 0]
        label = series_label(value, keys)
        color = "C%d" % j
        rp.measured(ax, grp, "level", "rays_level", label=label, color=color)
        rp.theory(ax, grp, "level", "rays_level_theory", color=color, ls=":")
        cal = [r for r in grp if first <= r["level"] <= last]
        k = sum(r["rays_level_mean"] for r in cal) / sum(r["rays_level_theory"] for r in cal) if cal else 1.0
        lv = rp.col(grp, "level")
        m = rp.col(grp, "rays_level_mean")
        law = rp.col(grp, "rays_level_theory")
        ax.plot(lv, [k * x for x in law], "--", color=color, lw=0.9)
        raw = [100 * (t - x) / x for x, t in zip(m, law)]
        calibrated = [100 * (k * t - x) / x for x, t in zip(m, law)]
        ax_e.plot(lv, raw, "o-", color=color, ms=3, label=label + ": law")
        ax_e.plot(lv, calibrated, "s--", color=color, ms=3, label=label + ": calibrated (×%.3f)" % k)
        below = [e for l, e in zip(lv, calibrated) if l > last]
        mid = [e for l, e in zip(lv, raw) if 1 <= l]
        print("%s: root r_0 = %.4g; raw law error over levels ≥ 1: %+.1f … %+.1f %%; "
              "calibrated on levels %d–%d (×%.3f), error over levels > %d: %+.1f … %+.1f %%"
              % (label, grp[0]["radius"], min(mid), max(mid), first, last, k, last,
                 min(below) if below else float("nan"), max(below) if below else float("nan")))
        for r, e, c in zip(grp, raw, calibrated):
            print("  level %2d radius %9.4g measured %12.1f ± %8.1f law %12.1f error %+6.1f %%, calibrated %+6.1f %%" % (
                r["level"], r["radius"], r["rays_level_mean"], r["rays_level_se"], r["rays_level_theory"], e, c))
    rp.log_scale(ax, y=True)
    ax.set_xlabel("level i")
    ax.set_ylabel("rays held by a level-i sphere")
    ax.legend(fontsize=7, title="dots: law n_R·(r_i/r_0)²; dashes: §4.1 calibrated", title_fontsize=7)
    ax_e.axhspan(-5, 5, color="0.9", label="±5 % (the paper's 'most levels')")
    ax_e.axhline(0, color="black", lw=0.8)
    ax_e.set_xlabel("level i")
    ax_e.set_ylabel("(law − measured) / measured, %")
    ax_e.legend(fontsize=6)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME, extra=extra)
