#!/usr/bin/env python3
"""The numbers docs/findings-detp.md quotes for the radius schedule, recomputed from the committed
table results/detp-radius-schedule-cornell.

Run from the repository root:  python3 scripts/radius_schedule_numbers.py [--results DIR]

For each (d_ref, β) it prints the RMSE against the reference (± SE) at every photon count and:
- the slope of log RMSE against log N (weighted least squares on the log means, weights from the
  SEs; interval: percentile bootstrap drawing every mean within its SE), with its χ²;
- for a fixed d (β = 0), the bias floor B of the model RMSE² = c/N + B (the crossover's error
  model), fitted by non-negative least squares on relative residuals, with its bootstrap interval;
- from the floors at two d_ref, the exponent α of the floor's growth, √B ∝ d^α (2 for a smooth
  field, whose disc average is off by (d²/8)·ΔE; 1/2 where the disc crosses a discontinuity, which a
  share ∝ d of the points does with an O(1) error), and what α implies for β (docs/theory.md).

Every statistic comes from scripts/raycost_stats.py; tables are read through
scripts/raycost_tables.py (the columns each meta.toml declares). Standard library only.
"""

import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import raycost_stats as S  # noqa: E402
import raycost_tables as T  # noqa: E402

NAME = "detp-radius-schedule-cornell"
DRAWS = 4000


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return v


def configurations(results):
    """{(d_ref, β): [(N, rmse, se), …]} in photon order."""
    rows = T.read_rows(os.path.join(results, NAME, NAME + ".csv"), num)[1]
    out = {}
    for r in rows:
        key = (r["detp.disc_radius"], r["detp.radius_schedule_exponent"])
        out.setdefault(key, []).append(
            (r["detp.photons"], r["irradiance_ref_rmse_mean"], r["irradiance_ref_rmse_se"]))
    return {k: sorted(v) for k, v in out.items()}


def slope(points):
    """The log-log slope, its 95 % interval and its fit's χ² on its residual dof."""
    xs = [p[0] for p in points]
    sampler = S.Parametric([p[1] for p in points], [p[2] for p in points])
    iv = S.bootstrap(S.log_slope_statistic(xs), sampler, draws=DRAWS)
    lx = [math.log(x) for x in xs]
    ly = [math.log(p[1]) for p in points]
    lv = [(p[2] / p[1]) ** 2 for p in points]
    _, _, chi2, dof = S.wls_line(lx, ly, lv)
    return iv, chi2, dof


def floor(points):
    """√B of RMSE² = c/N + B and its interval (None if the fit keeps B at 0)."""
    fit = S.fit_costs_ci([[1.0 / p[0] for p in points], [1.0] * len(points)],
                         [p[1] ** 2 for p in points], [2 * p[1] * p[2] for p in points],
                         draws=DRAWS)
    b, (lo, hi) = fit.constants[1], fit.cis[1]
    return math.sqrt(b), math.sqrt(max(lo, 0.0)), math.sqrt(max(hi, 0.0))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", default="results")
    a = ap.parse_args(argv)
    floors = {}
    for (d, beta), pts in sorted(configurations(a.results).items(), key=lambda kv: (kv[0][1], kv[0][0])):
        rule = "fixed" if beta == 0 else "N^(-%.3g)" % beta
        print("d_ref %g mm, %s:" % (d, rule))
        print("  " + "; ".join("%d: %.5f ± %.5f" % p for p in pts))
        iv, chi2, dof = slope(pts)
        print("  slope %.3f [%.3f, %.3f], chi2 %.1f on %d" % (iv.value, iv.lo, iv.hi, chi2, dof))
        last = S.bootstrap(S.log_slope_statistic([p[0] for p in pts[-2:]]),
                           S.Parametric([p[1] for p in pts[-2:]], [p[2] for p in pts[-2:]]), draws=DRAWS)
        print("  last octave pair %.3f [%.3f, %.3f]" % (last.value, last.lo, last.hi))
        if beta == 0:
            floors[d] = floor(pts)
            print("  floor sqrt(B) %.5f [%.5f, %.5f]" % floors[d])
    if len(floors) == 2:
        (d1, f1), (d2, f2) = sorted(floors.items())
        r = math.log(d2 / d1)
        alpha = math.log(f2[0] / f1[0]) / r
        lo = math.log(f2[1] / f1[2]) / r if f1[2] > 0 and f2[1] > 0 else math.nan
        hi = math.log(f2[2] / f1[1]) / r if f1[1] > 0 else math.inf
        print("floor exponent alpha (sqrt(B) ∝ d^alpha, from %g and %g mm): %.2f [%.2f, %.2f] "
              "(ends from the floors' interval ends)" % (d1, d2, alpha, lo, hi))
        print("  MSE-optimal beta = 1/(2·alpha + 2) = %.3f; its RMSE slope −alpha/(2·alpha + 2) = %.3f;"
              " at beta = 1/6 a bias-bound RMSE falls as N^(−alpha/6) = N^(%.3f)"
              % (1 / (2 * alpha + 2), -alpha / (2 * alpha + 2), -alpha / 6))


if __name__ == "__main__":
    main()
