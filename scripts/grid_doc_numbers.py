#!/usr/bin/env python3
"""The numbers docs/findings-grid.md quotes, recomputed from the committed grid tables.

Run from the repository root:  python3 scripts/grid_doc_numbers.py [--results DIR]

When the grid tables are regenerated (new random streams, new seeds), run this and copy what it
prints into docs/findings-grid.md (and the summary in docs/bench.md), so the prose never quotes a
table that is no longer committed. It reads only through scripts/raycost_tables.py (the columns
each meta.toml declares) and uses the standard library only. Definitions, as the findings use them:

- z = (mean − theory) / se, the standard errors as the tables give them (clustered);
- "the predictor is X % off" = theory / mean − 1 (positive: the predictor is high);
- timings (build_s, time_per_ray_s, t_i_s, t_s_s, wall_s) are printed with the run's
  `other_cores` (processes besides raycost, in cores): above ≈ 0.1 they are busy-machine figures.
"""

import argparse
import math
import os
import sys
import tomllib
from statistics import NormalDist

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import raycost_stats as S  # noqa: E402
import raycost_tables as T  # noqa: E402

GRID = ["grid-cell-width", "grid-first-hit", "grid-radius-classes", "grid-scaling",
        "grid-concentration", "grid-cost-model"]


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return v


def rows_of(results, name):
    return T.read_rows(os.path.join(results, name, name + ".csv"), num)[1]


def run_meta(results, name):
    with open(os.path.join(results, name, name + ".meta.toml"), "rb") as f:
        return tomllib.load(f).get("run", {})


def z(r, m):
    se = r[m + "_se"]
    return (r[m + "_mean"] - r[m + "_theory"]) / se if se and se == se else float("nan")


def zscores(rows, m):
    """(Σz², its χ² p on len(rows) dof, largest |z|) with each z turned into a normal score on its
    row's dof (clusters − 1), as the claims engine's z-gof rule does."""
    zs = [S.normal_score(z(r, m), S.dof(r, m)) for r in rows]
    q = sum(v * v for v in zs)
    return q, S.chi2_sf(q, len(zs)), max(abs(v) for v in zs)


def off(r, m, theory=None):
    """theory / mean − 1 of metric M (its own _theory column unless THEORY names another)."""
    return r[theory or (m + "_theory")] / r[m + "_mean"] - 1.0


def pct(x):
    return "%+.2f %%" % (100.0 * x)


def rng(values, fmt="%.2f"):
    values = [v for v in values if v == v]
    return (fmt + " … " + fmt) % (min(values), max(values)) if values else "–"


def rms(values):
    return math.sqrt(sum(v * v for v in values) / len(values))


def p_max_abs_z(zmax, k):
    """P(max |z| ≥ zmax over k independent standard normal z)."""
    tail = 2.0 * (1.0 - NormalDist().cdf(zmax))
    return 1.0 - (1.0 - tail) ** k


def head(title):
    print("\n== " + title)


def cell_width(results):
    rows = rows_of(results, "grid-cell-width")
    head("grid-cell-width (%d points)" % len(rows))
    small = [r for r in rows if r["predictor_regime"] == "r<a/2"]
    large = [r for r in rows if r["predictor_regime"] != "r<a/2"]
    inside = sum(r["n_i_mb_band"] == "inside" for r in rows)
    inside_plain = sum(r["n_i_band"] == "inside" for r in rows)
    print("mailboxed E[N_I] inside Result 3.1's band: %d of %d (no mailbox: %d)"
          % (inside, len(rows), inside_plain))
    band = [r["n_i_mb_upper"] / r["n_i_mb_lower"] for r in rows]
    print("band width upper/lower: %s" % rng(band, "%.1f"))
    mb = [abs(off(r, "n_i_mb")) for r in rows]
    print("mailboxed predictor |off|, all points (a/r = %s): %s %%"
          % (rng([r["grid.cell_width"] / r["scene.radius"] for r in rows], "%g"),
             rng([100 * v for v in mb])))
    print("mailboxed predictor |off| where r < a/2: max %.2f %%; where r >= a/2: max %.2f %%"
          % (100 * max(abs(off(r, "n_i_mb")) for r in small),
             100 * max(abs(off(r, "n_i_mb")) for r in large)))
    print("no-mailbox predictor |off| where r < a/2: max %.2f %%"
          % (100 * max(abs(off(r, "n_i")) for r in small)))
    for r in rows:
        if r["grid.cell_width"] == r["scene.radius"]:
            print("  a = r (rho %g, eye %s): n_i_theory %s, n_i_plain_theory %s"
                  % (r["scene.intensity"], r["grid.eye"], pct(off(r, "n_i")),
                     pct(off(r, "n_i", "n_i_plain_theory"))))
    for m in ("n_s", "t_hit"):
        zs = [z(r, m) for r in rows]
        worst = max(range(len(rows)), key=lambda i: abs(zs[i]))
        w = rows[worst]
        print("%s: |z| <= 2 at %d of %d; |z| > 3 at %d; rms z %.2f; largest |z| %.2f at point %d "
              "(rho %g, a %g, eye %s): z(N_S) %+.2f, z(t*) %+.2f, KS p %.3g; "
              "P(max |z| >= that over %d points) = %.3f"
              % (m, sum(abs(v) <= 2 for v in zs), len(rows), sum(abs(v) > 3 for v in zs),
                 rms(zs), abs(zs[worst]), w["point"], w["scene.intensity"], w["grid.cell_width"],
                 w["grid.eye"], z(w, "n_s"), z(w, "t_hit"), w["t_hit_ks_p"], len(rows),
                 p_max_abs_z(abs(zs[worst]), len(rows))))
        others = [(int(r["point"]), v) for r, v in zip(rows, zs) if 2 < abs(v) and r is not w]
        print("  other points beyond 2 SE: %s"
              % (", ".join("point %d (%+.2f)" % o for o in others) or "none"))
    q, p, largest = zscores(rows, "t_hit")
    print("t* as the claims engine sees it (normal scores on clusters − 1 dof): "
          "Σz² %.1f on %d dof, p %.3f, largest |z| %.2f" % (q, len(rows), p, largest))
    print("clusters per point: %s (rays per point %s)"
          % (rng([r["t_hit_clusters"] for r in rows], "%d"),
             rng([r["experiment.rays"] for r in rows], "%d")))
    ks = sorted((r["t_hit_ks_p"], int(r["point"])) for r in rows)
    print("KS p < 0.01 at %d points (%s)"
          % (sum(p < 0.01 for p, _ in ks),
             ", ".join("point %d: %.2g" % (i, p) for p, i in ks if p < 0.01) or "none"))


def first_hit(results):
    rows = rows_of(results, "grid-first-hit")
    head("grid-first-hit (%d points)" % len(rows))
    for r in rows:
        print("a %g, r %g: KS p %.3g, z(t*) %+.2f, z(N_S) %+.2f, chi2 p of N_I,mb geometric %.3g, "
              "mailboxed predictor %s (%s), n_i_band %s, n_i_mb_band %s"
              % (r["grid.cell_width"], r["scene.radius"], r["t_hit_ks_p"], z(r, "t_hit"),
                 z(r, "n_s"), r["n_i_mb_chi2_p"], pct(off(r, "n_i_mb")), r["predictor_regime"],
                 r["n_i_band"], r["n_i_mb_band"]))
    print("largest |z(t*)| %.2f" % max(abs(z(r, "t_hit")) for r in rows))


def radius_classes(results):
    rows = rows_of(results, "grid-radius-classes")
    head("grid-radius-classes (%d points)" % len(rows))
    print("inside the integrated band: mailboxed %d, no mailbox %d of %d"
          % (sum(r["n_i_mb_band"] == "inside" for r in rows),
             sum(r["n_i_band"] == "inside" for r in rows), len(rows)))
    for draw in sorted({r["scene.radius_draw"] for r in rows}):
        for r in sorted((r for r in rows if r["scene.radius_draw"] == draw),
                        key=lambda r: r["grid.cell_width"]):
            print("%s a %g: mailboxed predictor %s z %+.2f; no mailbox %s z %+.2f; "
                  "z(N_S) %+.2f, z(t*) %+.2f"
                  % (draw, r["grid.cell_width"], pct(off(r, "n_i_mb")), z(r, "n_i_mb"),
                     pct(off(r, "n_i")), z(r, "n_i"), z(r, "n_s"), z(r, "t_hit")))


def pooled_first_hit(results):
    """t* against E[t*] and the KS test over every infinite-scene point (independent rays)."""
    rows = []
    for name in ("grid-cell-width", "grid-first-hit", "grid-radius-classes"):
        rows += rows_of(results, name)
    head("t* over the infinite-scene tables together (%d points)" % len(rows))
    q, p, largest = zscores(rows, "t_hit")
    ks = [r["t_hit_ks_p"] for r in rows]
    print("Σz² %.1f on %d dof, p %.3f, largest |z| %.2f; KS p < 0.05 at %d, < 0.01 at %d points"
          % (q, len(rows), p, largest, sum(v < 0.05 for v in ks), sum(v < 0.01 for v in ks)))


def scaling(results):
    rows = sorted(rows_of(results, "grid-scaling"), key=lambda r: r["scene.spheres"])
    meta = run_meta(results, "grid-scaling")
    head("grid-scaling (%d points; timings: other_cores %s)"
         % (len(rows), meta.get("other_cores")))
    for r in rows:
        print("n %.0e: z(N_I) %+.2f, z(N_I,mb) %+.2f, z(N_S) %+.2f; hit %.4f (theory %.4f); "
              "brute force %d rays, %d mismatches; %.3g listings, %.3g GB; build %.3g s"
              % (r["scene.spheres"], z(r, "n_i"), z(r, "n_i_mb"), z(r, "n_s"), r["hit_mean"],
                 r["hit_theory"], r["bf_rays"], r["bf_mismatches"], r["grid_listings"],
                 r["grid_bytes"] / 1e9, r["build_s"]))
    print("brute force: %d rays checked, %d mismatches"
          % (sum(r["bf_rays"] for r in rows if r["bf_rays"] == r["bf_rays"]),
             sum(r["bf_mismatches"] for r in rows if r["bf_mismatches"] == r["bf_mismatches"])))


def concentration(results):
    rows = rows_of(results, "grid-concentration")
    head("grid-concentration (%d points)" % len(rows))
    for c in sorted({r["scaling.c"] for r in rows}):
        sub = sorted((r for r in rows if r["scaling.c"] == c), key=lambda r: r["scene.spheres"])
        print("c %g:" % c)
        for r in sub:
            print("  n %.0e: E[N_I] %.2f, E[N_I,mb] %.2f, P(N_I >= c ln n) %.4g, "
                  "P(N_I >= c sqrt n) %.4g, rays %d"
                  % (r["scene.spheres"], r["n_i_mean"], r["n_i_mb_mean"], r["p_log_mean"],
                     r["p_sqrt_mean"], r["p_sqrt_n"]))
        zero = [r["scene.spheres"] for r in sub if r["p_sqrt_mean"] == 0]
        print("  sqrt tail 0 from n = %s" % ("%.0e" % min(zero) if zero else "never"))
    big = [r for r in rows if r["scene.spheres"] >= 1000]
    print("from n = 1e3: E[N_I] %s, E[N_I,mb] %s"
          % (rng([r["n_i_mean"] for r in big]), rng([r["n_i_mb_mean"] for r in big])))


def cost_model(results):
    rows = sorted(rows_of(results, "grid-cost-model"), key=lambda r: r["grid.cell_width"])
    meta = run_meta(results, "grid-cost-model")
    head("grid-cost-model (%d points; timings: threads %s, other_cores %s)"
         % (len(rows), meta.get("threads"), meta.get("other_cores")))
    r0 = rows[0]
    print("T_I %.2f ns, T_S %.2f ns" % (r0["t_i_s"] * 1e9, r0["t_s_s"] * 1e9))
    best_model = min(rows, key=lambda r: r["time_model_s"])
    best_timed = min(rows, key=lambda r: r["time_per_ray_s"])
    print("model's best a %g (%.3f us); timed minimum at a %g (%.3f us)"
          % (best_model["grid.cell_width"], best_model["time_model_s"] * 1e6,
             best_timed["grid.cell_width"], best_timed["time_per_ray_s"] * 1e6))
    for r in rows:
        print("  a %g: timed %.3f us (%s of the minimum), model %.3f us, timed / model %.2f"
              % (r["grid.cell_width"], r["time_per_ray_s"] * 1e6,
                 pct(r["time_per_ray_s"] / best_timed["time_per_ray_s"] - 1),
                 r["time_model_s"] * 1e6, r["time_per_ray_s"] / r["time_model_s"]))
    print("timed / model: %s" % rng([r["time_per_ray_s"] / r["time_model_s"] for r in rows]))


def wall_times(results):
    head("wall time of each run ([run] wall_s; other_cores = other processes, in cores)")
    for name in GRID + ["quickstart"]:
        path = os.path.join(results, name, name + ".meta.toml")
        if os.path.exists(path):
            m = run_meta(results, name)
            print("%-20s %8.1f s  threads %s  other_cores %s"
                  % (name, m.get("wall_s", float("nan")), m.get("threads"), m.get("other_cores")))


def stream_change(before, after):
    """Before → after over the infinite-scene tables, for a note on regenerated streams: the largest
    |z| of N_S and t*, the points beyond 3 SE, the points inside the bands, KS rejections, and
    (after − before)/√(SE² + SE²) of each mean (both runs estimate the same means)."""
    head("before (%s) → after (%s)" % (before, after))
    for name in ("quickstart", "grid-cell-width", "grid-first-hit", "grid-radius-classes"):
        try:
            old, new = rows_of(before, name), rows_of(after, name)
        except (T.TableError, OSError):
            continue
        def summary(rows):
            zn, zt = [abs(z(r, "n_s")) for r in rows], [abs(z(r, "t_hit")) for r in rows]
            return ("%.2f, %.2f" % (max(zn), max(zt)),
                    "%d, %d" % (sum(v > 3 for v in zn), sum(v > 3 for v in zt)),
                    "%d, %d" % (sum(r["n_i_band"] == "inside" for r in rows),
                                sum(r["n_i_mb_band"] == "inside" for r in rows)),
                    "%d" % sum(r["t_hit_ks_p"] < 0.01 for r in rows))
        b, a = summary(old), summary(new)
        d = [(n[m + "_mean"] - o[m + "_mean"]) / math.hypot(n[m + "_se"], o[m + "_se"])
             for o, n in zip(old, new) for m in ("n_i", "n_i_mb", "n_s", "t_hit")]
        print("%s (%d): max |z| N_S, t* %s → %s; |z| > 3 %s → %s; inside the band (plain, "
              "mailboxed) %s → %s; KS p < 0.01 %s → %s; new − old: rms %.2f, largest |·| %.2f"
              % (name, len(new), b[0], a[0], b[1], a[1], b[2], a[2], b[3], a[3], rms(d),
                 max(abs(v) for v in d)))


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", default="results", help="the results folder (default: results)")
    ap.add_argument("--before", metavar="DIR",
                    help="also compare with the same tables in DIR (e.g. the previous commit's "
                         "results extracted with git show), after new random streams")
    args = ap.parse_args(argv)
    try:
        for f in (cell_width, first_hit, radius_classes, pooled_first_hit, scaling, concentration, cost_model,
                  wall_times):
            f(args.results)
        if args.before:
            stream_change(args.before, args.results)
    except (T.TableError, OSError, KeyError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
