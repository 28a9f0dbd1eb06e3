#!/usr/bin/env python3
"""Which method when: the output of `raycost crossover` for one scene
(results/crossover-SCENE/crossover.csv, with best.csv and, for a frames run, frames.csv
beside it).

One panel per target relative RMSE: seconds to reach the target at n_P points, 10² … 10⁶, for
per-point path tracing (paths per point × seconds per path × n_P: a straight line) and every
configuration the n_P sweep timed (DETP engines by direct light, edge mode and d; photon maps), each
at the photons its error fit needs (N_ε, `photons`), from its fitted cost model
T = fixed + a·N + b·N·n_P^γ + c·n_P. Configurations that cannot reach the target (error floor, or no
cost sweep) are absent; crossover.csv says why. A marker with a horizontal bar on the path-tracing
line shows each DETP configuration's N* with its 95 % bootstrap interval (replicas' errors and the
cost model's residuals). With frames.csv a last panel draws the total seconds of F frames at the
middle target for each frames run's point count: DETP incremental (first frame + F − 1 incremental
ones), DETP in full every frame, and path tracing every frame.
"""

import math
import os

import raycost_plot as rp

NAME = "crossover-cornell"
REQUIRED = ["scene", "target", "method", "direct", "edge", "disc_radius", "photons", "seconds_per_point",
            "cost_gamma", "cost_fixed", "cost_per_photon", "cost_per_photon_point", "cost_per_point",
            "n_star", "n_star_lo", "n_star_hi", "reason"]
POINTS = [10 ** (2 + k / 8) for k in range(33)]


def finite(x):
    return isinstance(x, (int, float)) and x == x and not math.isinf(x)


def label(r):
    """A configuration's name, as best.csv writes it."""
    if r["method"] == "path-tracing":
        return "path tracing"
    out = r["method"] + (", NEE direct" if r["direct"] == "nee" else "")
    if finite(r["disc_radius"]):
        out += ", %s, d = %g" % (r["edge"], r["disc_radius"])
    return out


def seconds(r, n_p):
    """T(N_ε, n_P) of a row, or None."""
    if r["method"] == "path-tracing":
        return r["seconds_per_point"] * n_p if finite(r["seconds_per_point"]) else None
    if not (finite(r["photons"]) and finite(r["cost_gamma"])):
        return None
    n = r["photons"]
    return (r["cost_fixed"] + r["cost_per_photon"] * n + r["cost_per_photon_point"] * n * n_p ** r["cost_gamma"]
            + r["cost_per_point"] * n_p)


def target_panel(ax, rows, target):
    mine = [r for r in rows if r["target"] == target and seconds(r, 1e4) is not None]
    mine.sort(key=lambda r: (r["method"] != "path-tracing", label(r)))
    pt = next((r for r in mine if r["method"] == "path-tracing"), None)
    for i, r in enumerate(mine):
        style = {"path-tracing": "-", "sphere-cache": "-", "disc-index": "--"}.get(r["method"], ":")
        color = "k" if r["method"] == "path-tracing" else "C%d" % (i % 10)
        ax.plot(POINTS, [seconds(r, p) for p in POINTS], style, color=color, lw=2 if pt is r else 1.2,
                label="%s (%s)" % (label(r), "%d paths" % r["photons"] if r is pt else "N = %.2g" % r["photons"]))
        if pt is not None and r is not pt and finite(r["n_star"]):
            x = r["n_star"]
            # No bootstrap (photon maps): the marker alone; an unbounded end (+inf): to the edge,
            # or nothing where N* itself lies past the edge.
            lo = r["n_star_lo"] if finite(r["n_star_lo"]) else x
            edge = max(POINTS[-1], x)
            hi = r["n_star_hi"] if finite(r["n_star_hi"]) else (edge if r["n_star_hi"] == math.inf else x)
            ax.errorbar([x], [seconds(pt, x)], xerr=[[x - lo], [hi - x]], fmt="o", color=color, ms=5,
                        capsize=3)
            print("target %g: %-48s N* = %.4g [%.4g, %.4g]" % (target, label(r), x, lo, hi))
    ax.set_xlim(POINTS[0], POINTS[-1])
    rp.log_scale(ax, x=True, y=True)
    ax.set_title("target relative RMSE %g %%" % (100 * target), fontsize=9)
    ax.set_xlabel("points n_P")
    ax.set_ylabel("seconds to reach the target")
    ax.legend(fontsize=5)


def frames_panel(ax, path, target):
    rows = [r for r in rp.read_csv(path, ["target", "points", "first_s", "frame_s", "full_s",
                                           "path_tracing_frame_s"]) if r["target"] == target]
    seen = set()
    frames = list(range(1, 101))
    for i, r in enumerate(rows):
        if r["points"] in seen or not finite(r["first_s"]):
            continue
        seen.add(r["points"])
        c = "C%d" % (i % 10)
        ax.plot(frames, [r["first_s"] + (f - 1) * r["frame_s"] for f in frames], "-", color=c,
                label="DETP incremental, %d points" % r["points"])
        ax.plot(frames, [f * r["full_s"] for f in frames], "--", color=c, label="DETP full per frame")
        ax.plot(frames, [f * r["path_tracing_frame_s"] for f in frames], ":", color=c, lw=2,
                label="path tracing per frame")
    rp.log_scale(ax, x=True, y=True)
    ax.set_title("F frames at %g %% per frame" % (100 * target), fontsize=9)
    ax.set_xlabel("frames F")
    ax.set_ylabel("total seconds")
    ax.legend(fontsize=5)


def plot(args):
    rows = rp.read_csv(args.input, REQUIRED)
    targets = sorted({r["target"] for r in rows}, reverse=True)
    frames = os.path.join(os.path.dirname(args.input), "frames.csv")
    has_frames = os.path.exists(frames)
    fig, axes = rp.subplots(1, len(targets) + (1 if has_frames else 0), panel_w=5.5, panel_h=4.4)
    for k, t in enumerate(targets):
        target_panel(axes[0][k], rows, t)
    if has_frames:
        frames_panel(axes[0][-1], frames, targets[len(targets) // 2])
    fig.suptitle("%s: which method when" % rows[0]["scene"], fontsize=10)
    rp.finish(fig, args)


if __name__ == "__main__":
    rp.script(plot, __doc__, NAME)
