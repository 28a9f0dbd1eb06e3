#!/usr/bin/env python3
"""The loose numbers docs/findings-detp.md quotes outside the claims and the radius schedule,
recomputed from the committed tables: each is printed as the phrase the findings use, and
scripts/tests/test_detp_doc_numbers.py fails when a phrase is not in the findings word for word.

Run from the repository root:  python3 scripts/detp_doc_numbers.py [--results DIR]

- cornell-levels: the surface points skipped as covered (column points_covered).
- speed-vs-error, per scene: DETP's and the photon map's relative bias and RMSE over photon counts
  and d (the relative figures scripts/plot_speed_vs_error.py prints and plots: one definition), the
  points lying within d of another surface (edge_distance < disc_radius in the points table), and on
  the robots the points where the reference is exactly 0 and those where DETP is exactly 0 too.
- predict-engine: the frames at which the separate runs (same seed, same photons; the pick is taken
  on seconds) picked different engines.
- nstar-crossover-{cornell,museum}: the refined sweeps' N* with their intervals where a head-to-head
  run measured the crossing, and the measured crossing over the predicted point.

Tables are read through scripts/raycost_tables.py (the columns each meta.toml declares).
"""

import argparse
import os
import re
import sys
import tomllib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import plot_speed_vs_error as sve  # noqa: E402
import raycost_plot as rp  # noqa: E402

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
KITCHEN = "scenes/bart/kitchen/kitchen.aff"
ROBOTS = "scenes/bart/robot/Robot.aff"


def pct(x, digits=1):
    """A signed percentage as the findings write it: +5.4, −16 (Unicode minus)."""
    s = "%+.*f" % (digits, 100 * x)
    return s.replace("-", "−")


def count(n):
    """An integer as the findings write it: 1 482 (a space between thousands)."""
    return "{:,}".format(n).replace(",", " ")


def span(values, fmt):
    """'lo–hi' of the values, each through fmt."""
    return "%s–%s" % (fmt(min(values)), fmt(max(values)))


def covered_points(results):
    rows = rp.read_csv(os.path.join(results, "cornell-levels", "cornell-levels.csv"), ["points_covered"])
    return ["%s points covered by the blocks skipped" % count(int(rows[0]["points_covered"]))]


def speed_vs_error(results):
    """(rows of the sweep, {(method, setting, photons) per scene: relative figures}, points table)."""
    path = os.path.join(results, "speed-vs-error", "speed-vs-error.csv")
    rows = rp.read_csv(path, sve.REQUIRED + ["detp.scene", "detp.edge"])
    points = rp.read_csv(rp.sibling_csv(path, "points"),
                         ["point", "disc_radius", "edge_distance", "reference_e", "irradiance_mean"])
    conf = {}
    for scene in sorted({r["detp.scene"] for r in rows}):
        conf[scene] = sve.configurations([r for r in rows if r["detp.scene"] == scene])
    return rows, conf, points


def figures(conf, method, edge):
    """[(relative RMSE, its CI half-width, relative bias, its CI half-width)] of one method (DETP:
    the sphere cache's rows, the same estimate as the disc index's) at the given edge rule, in
    photon order."""
    out = []
    for (m, setting, photons), (_, rmse, rmse_h, bias, bias_h) in sorted(conf.items(), key=lambda kv: kv[0][2]):
        if m == method and (edge is None or setting.endswith(", " + edge)):
            out.append((rmse, rmse_h, bias, bias_h))
    return out


def kitchen_quotes(conf, rows, points):
    detp = figures(conf[KITCHEN], "DETP sphere cache", "paper")
    pm = figures(conf[KITCHEN], "photon map", None)
    within = within_d(rows, points, KITCHEN)
    return [
        "**%s … %s %%** at every photon count and d (95 %% CIs ± %s %%" % (
            pct(min(f[2] for f in detp)), pct(max(f[2] for f in detp)),
            span([f[3] for f in detp], lambda x: "%.1f" % (100 * x))),
        "its relative RMSE %s (± %s" % (span([f[0] for f in detp], lambda x: "%.2f" % x),
                                         span([f[1] for f in detp], lambda x: "%.2f" % x)),
        "The photon map's bias moves from %s %% to %s %% with photons (k fixed), its RMSE %s" % (
            pct(pm[0][2]), pct(pm[-1][2], 0), span([f[0] for f in pm], lambda x: "%.2f" % x)),
        "%s and %s of the %s points lie within d = %s and %s cm of another surface" % within,
    ]


def within_d(rows, points, scene):
    """(points within the smaller d, within the larger, all points, the two d in cm) of one scene:
    edge_distance < disc_radius (scene units: metres), counted at the first sweep point of each d
    (every sweep point of a scene has the same points)."""
    first = {}
    for r in rows:
        if r["detp.scene"] == scene:
            first.setdefault(r["detp.disc_radius"], int(r["point"]))
    counts, mine_d, total = [], [], 0
    for d in sorted(first):
        mine = [p for p in points if int(p["point"]) == first[d]]
        counts.append(sum(1 for p in mine if p["edge_distance"] < p["disc_radius"]))
        mine_d.append(mine[0]["disc_radius"])
        total = len(mine)
    cm = ["%g" % round(100 * d, 3) for d in (mine_d[0], mine_d[-1])]
    return count(counts[0]), count(counts[-1]), count(total), cm[0], cm[1]


def robots_quotes(conf, rows, points):
    paper = figures(conf[ROBOTS], "DETP sphere cache", "paper")
    clamp = figures(conf[ROBOTS], "DETP sphere cache", "clamp-first-hit")
    robot_points = {int(r["point"]): r["detp.edge"] for r in rows if r["detp.scene"] == ROBOTS}
    first = min(robot_points)
    mine = [p for p in points if int(p["point"]) == first]
    dark = sum(1 for p in mine if p["reference_e"] == 0)
    both = [sum(1 for p in points if int(p["point"]) == k and p["reference_e"] == 0 and p["irradiance_mean"] == 0)
            for k, edge in robot_points.items() if edge == "clamp-first-hit"]
    return [
        "relative bias is **%s … %s %%** (RMSE %s× the mean)" % (
            pct(min(f[2] for f in paper), 0), pct(max(f[2] for f in paper), 0),
            span([f[0] for f in paper], lambda x: "%.0f" % x)),
        "with `clamp-first-hit` %s … %s %% (RMSE %s×)" % (
            pct(min(f[2] for f in clamp), 0), pct(max(f[2] for f in clamp), 0),
            span([f[0] for f in clamp], lambda x: "%.2g" % x)),
        "the reference is exactly 0 at %s of the %s points" % (count(dark), count(len(mine))),
        "DETP is 0 at %s of those %s points" % (span(both, count), count(dark)),
    ]


def predictor_quotes(results):
    runs = sorted(os.listdir(os.path.join(results, "predict-engine", "runs")), key=int)
    picks = []
    for k in runs:
        frames = rp.read_csv(os.path.join(results, "predict-engine", "runs", k, "predict-engine.frames.csv"),
                             ["point", "replica", "frame", "engine_used"])
        picks.append({(r["point"], r["replica"], r["frame"]): r["engine_used"] for r in frames if r["frame"] >= 1})
    keys = sorted(picks[0])
    pairs = [sum(1 for key in keys if a[key] != b[key]) for i, a in enumerate(picks) for b in picks[i + 1:]]
    any_differs = sum(1 for key in keys if len({p[key] for p in picks}) > 1)
    return ["the %d separate runs picked differently at %s of %d frames pairwise (%d differ in at least one)"
            % (len(picks), span(pairs, count), len(keys), any_differs)]


SUPERSCRIPT = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")


def sci(x):
    """A number as the findings write it, two significant digits: 4.9·10³."""
    mantissa, exponent = ("%.1e" % x).split("e")
    return "%s·10%s" % (mantissa, str(int(exponent)).translate(SUPERSCRIPT))


def nstar_quotes(results):
    """Per scene with a head-to-head run: each confirmed engine's refined N* [interval] and the
    measured crossing over that point."""
    out = []
    ratios = {}
    for scene in ["cornell", "museum"]:
        rows = rp.read_csv(os.path.join(results, "nstar-crossover-%s" % scene, "crossover.csv"),
                           ["method", "n_star", "n_star_lo", "n_star_hi", "n_star_head_to_head"])
        confirmed = [r for r in rows if r["n_star_head_to_head"] == r["n_star_head_to_head"]]  # not NaN
        order = {"disc-index": 0, "sphere-cache": 1}
        for r in sorted(confirmed, key=lambda r: order[r["method"]]):
            out.append("%s [%s, %s]" % (sci(r["n_star"]), sci(r["n_star_lo"]), sci(r["n_star_hi"])))
            ratios.setdefault(scene, []).append("%.2f×" % (r["n_star_head_to_head"] / r["n_star"]))
    c, m = ratios["cornell"], ratios["museum"]
    out.append("at %s and %s the point prediction on the Cornell box and %s and %s on the museum"
               % (c[0], c[1], m[0], m[1]))
    return out


def facing_quotes(results):
    """The fixed kitchen points facing into another surface closer than d along their normal, as
    fronts-kitchen's metadata warns for its sweep points (each warning names its first point, whose
    d the table gives, in metres)."""
    with open(os.path.join(results, "fronts-kitchen", "fronts-kitchen.meta.toml"), "rb") as f:
        meta = tomllib.load(f)
    rows = rp.read_csv(os.path.join(results, "fronts-kitchen", "fronts-kitchen.csv"), ["point", "detp.disc_radius"])
    d_of = {int(r["point"]): r["detp.disc_radius"] for r in rows}
    pattern = r"^points? (\d+)\D.*?: (\d+) of (\d+) points of (\S+) have a normal facing into"
    found = sorted({(d_of[int(m.group(1))], int(m.group(2)), int(m.group(3)), m.group(4))
                    for m in (re.search(pattern, w) for w in meta.get("warnings", [])) if m})
    return ["%s of the %s points of `%s` are (d = %s cm)" % (
        " and ".join(count(f[1]) for f in found), count(found[0][2]), found[0][3],
        " and ".join("%g" % round(100 * f[0], 3) for f in found))]


def quotes(results):
    """[(the doc under docs/, the phrase it must hold)]."""
    rows, conf, points = speed_vs_error(results)
    findings = (covered_points(results) + kitchen_quotes(conf, rows, points) + robots_quotes(conf, rows, points)
                + predictor_quotes(results) + nstar_quotes(results))
    return [("findings-detp.md", q) for q in findings] + [("reference.md", q) for q in facing_quotes(results)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--results", default=os.path.join(ROOT, "results"))
    args = ap.parse_args(argv)
    for doc, q in quotes(args.results):
        print("%s: %s" % (doc, q))
    return 0


if __name__ == "__main__":
    rp.run(lambda: sys.exit(main()))
