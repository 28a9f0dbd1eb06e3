"""Writes error_fit_cases.txt: seeded relative-MSE samples at photon counts spanning decades, from
known floors B and variances c (MSE = B + c/N, with up to ±40 % noise, one case with a value at or
below 0 and one with a NaN), and Python's error-model fit of each (raycost_stats.fit_relative_iterated),
which the Python test (test_stats.ErrorFitShared) and the Rust test (stats::fit,
`the_error_fit_equals_the_python_copy`) both hold their fit to.
Run from the repository root: python3 scripts/tests/data/make_error_fit_cases.py
"""
import random
import sys

sys.path.insert(0, "scripts")  # run from the repository root
import raycost_stats as S  # noqa: E402

rng = random.Random(20261204)
# (B, c, noise): a floor reached, a floor hidden under the variance, no floor, and a pure floor.
truths = [(1e-4, 50.0, 0.0), (1e-4, 50.0, 0.2), (2e-6, 400.0, 0.3), (0.0, 10.0, 0.4),
          (3e-2, 1e-3, 0.1), (1e-5, 20.0, 0.2)]
out = ["# The error model MSE(N) = B + c/N (non-negative least squares weighted by 1/fitted², iterated",
       "# from the measured values), held equal in Python (raycost_stats.fit_relative_iterated) and Rust",
       "# (stats::fit::ErrorFit::fit_relative) on shared inputs. Written once by a seeded generator; each",
       "# case: 'case', rows 'sample PHOTONS MSE', then 'expect B C' (Python's fit)."]
photons = [2.5e4, 5e4, 1e5, 2e5, 4e5, 8e5, 1.6e6, 3.2e6, 6.4e6]
for k, (b, c, noise) in enumerate(truths):
    out.append("case")
    ns, ys = [], []
    for n in photons:
        y = (b + c / n) * (1 + noise * (2 * rng.random() - 1))
        if k == 2 and n == photons[-1]:
            y = -1e-7  # the reference's variance subtracted from a tiny MSE
        if k == 5 and n == photons[3]:
            y = float("nan")
        ns.append(n)
        ys.append(y)
        out.append("sample %r %r" % (n, y))
    coef, _ = S.fit_relative_iterated([[1.0] * len(ns), [1.0 / n for n in ns]], ys)
    out.append("expect %r %r" % tuple(coef))
open("scripts/tests/data/error_fit_cases.txt", "w").write("\n".join(out) + "\n")
