#!/usr/bin/env python3
"""Amortisation of the static disc index (experiment quasi-static-amortisation; the paper cites 180 to
about 7000 frames). For every (d, photons): frame 0 (the full trace and gather, the index's build
included) and the static points' update per later frame, with the index (detp.engine = disc-index) and
with a sphere cache (sphere-cache). Frames to pay for the index F* = (its build seconds) / (update
without − update with), unclipped (the statistic of claims/preregistered.toml, rule amortisation):
negative when the index saves nothing per frame. Means and SEs across replicas (frame 0 from
NAME.frames.csv, one row per replica); the CI of F* is Fieller's, Student-t on the replicas (the
build is one value per point: no SE). Left: frame 0 per engine; middle: update per frame; right: F*
against 180 … 7000.
"""
import math

import raycost_plot as rp
from raycost_stats import dof, fieller, frame0, t95

NAME = "quasi-static-amortisation"
REQUIRED = ["detp.engine", "static_s_mean", "static_s_se", "static_s_n", "frame0_s", "static_index_build_s"]


def plot(args):
    rows, frames = rp.with_params(args.input, "frames", ["frame", "frame_s"])
    rp.require_columns(args.input, rows[0].keys(), REQUIRED)
    d_key = "detp.disc_radius" if rp.has(rows, "detp.disc_radius") else None
    n_key = "detp.photons" if rp.has(rows, "detp.photons") else None
    keys = [k for k in (d_key, n_key) if k]
    _, groups = rp.group_by(rows, *keys)
    fig, axes = rp.subplots(1, 3, panel_w=5.0, panel_h=4.2)
    ax0, ax_u, ax_f = axes[0]
    labels, f_mid, f_lo, f_hi = [], [], [], []
    for i, (value, grp) in enumerate(groups.items()):
        by = {r["detp.engine"]: r for r in grp}
        if "disc-index" not in by or "sphere-cache" not in by:
            continue
        di, sc = by["disc-index"], by["sphere-cache"]
        f_di, f_sc = frame0(frames, di["point"]), frame0(frames, sc["point"])
        reps = min(f_di[2], f_sc[2])
        z = t95(reps - 1)
        label = ", ".join("%s = %g" % (k.split(".")[-1], v) for k, v in zip(keys, value))
        labels.append(label)
        ax0.errorbar([i - 0.1], [f_di[0]], yerr=[z * f_di[1]], fmt="s", color="C1", label="disc index" if i == 0 else None)
        ax0.errorbar([i + 0.1], [f_sc[0]], yerr=[z * f_sc[1]], fmt="o", color="C0", label="sphere cache" if i == 0 else None)
        ax_u.errorbar([i - 0.1], [di["static_s_mean"]], yerr=[z * di["static_s_se"]], fmt="s", color="C1",
                      label="disc index" if i == 0 else None)
        ax_u.errorbar([i + 0.1], [sc["static_s_mean"]], yerr=[z * sc["static_s_se"]], fmt="o", color="C0",
                      label="sphere cache" if i == 0 else None)
        saving = sc["static_s_mean"] - di["static_s_mean"]
        v_saving = sc["static_s_se"] ** 2 + di["static_s_se"] ** 2
        tq = t95(min(dof(di, "static_s"), dof(sc, "static_s")))
        f, lo, hi, _ = fieller(di["static_index_build_s"], 0.0, saving, v_saving, 0.0, tq)
        f_mid.append(f)
        f_lo.append(lo)
        f_hi.append(hi)
        print("%s: frame 0 %.3f ± %.3f s (index) vs %.3f ± %.3f s (sphere cache); update %.4f ± %.4f vs %.4f ± %.4f s per frame; "
              "index build %.4f s; build ÷ saving %s [%s, %s] frames (95 %% Fieller CI, %d replicas)" % (
                  label, f_di[0], f_di[1], f_sc[0], f_sc[1], di["static_s_mean"], di["static_s_se"],
                  sc["static_s_mean"], sc["static_s_se"], di.get("static_index_build_s", float("nan")),
                  "%.3g" % f, "%.3g" % lo, "%.3g" % hi, reps))
    xs = list(range(len(labels)))
    for a in (ax0, ax_u, ax_f):
        a.set_xticks(xs)
        a.set_xticklabels(labels, rotation=30, ha="right", fontsize=7)
    ax0.set_ylabel("frame 0 seconds (mean ± 95 % CI)")
    ax_u.set_ylabel("static update seconds per frame")
    for a in (ax0, ax_u):
        a.set_yscale("log")
        a.legend(fontsize=7)
    shown = [max(v, 1e-3) for v in f_mid]
    err = [[max(m - lo, 0) if math.isfinite(m) else 0 for m, lo in zip(f_mid, f_lo)],
           [max(hi - m, 0) if math.isfinite(hi) and math.isfinite(m) else 0 for m, hi in zip(f_mid, f_hi)]]
    ax_f.errorbar(xs, shown, yerr=err, fmt="o", color="C3", label="index build ÷ saving per frame (≤ 0 drawn at 0.001)")
    ax_f.axhspan(180, 7000, color="0.9", label="the paper: 180 … 7000 frames")
    ax_f.set_yscale("log")
    ax_f.set_ylabel("frames until the index has paid for itself")
    ax_f.legend(fontsize=7)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
