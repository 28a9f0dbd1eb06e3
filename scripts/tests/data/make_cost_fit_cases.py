"""Writes cost_fit_cases.txt: seeded DETP-like cost samples (three photon counts × five point
counts, from known coefficients with up to ±30 % noise) and Python's cost fit of each, which the
Python test (test_stats.CostFitShared) and the Rust test (stats::fit, `the_cost_fit_equals_the_python_copy`)
both hold their fit to. Run from the repository root: python3 scripts/tests/data/make_cost_fit_cases.py
"""
import random, sys
sys.path.insert(0, 'scripts')  # run from the repository root
import raycost_stats as S
rng = random.Random(20261129)
cases = []
# (fixed, per_photon, per_photon_point, per_point, gamma, noise)
truths = [(0.05, 2e-7, 3e-12, 4e-6, 1.0, 0.0),
          (0.05, 2e-7, 3e-12, 4e-6, 1.0, 0.10),
          (0.2, 5e-7, 2e-10, 1e-5, 0.5, 0.10),
          (0.0, 3e-7, 0.0, 2e-6, 0.25, 0.05),
          (1.0, 1e-7, 1e-11, 0.0, 0.75, 0.30)]
out = ["# The cost fit seconds = fixed + a·N + b·N·n_P^γ + c·n_P (non-negative least squares on",
       "# relative residuals), held equal in Python (raycost_stats.fit_costs) and Rust",
       "# (stats::fit::CostModel::fit) on shared inputs. Written once by a seeded generator; each",
       "# case: 'case GAMMA', rows 'sample PHOTONS POINTS SECONDS', then 'expect FIXED A B C' (Python's fit).",
       ]
for (f, a, b, c, g, noise) in truths:
    out.append("case %r" % g)
    samples = []
    for n in (5e4, 2e5, 8e5):
        for p in (1e2, 1e3, 1e4, 1e5, 1e6):
            s = (f + a * n + b * n * p ** g + c * p) * (1 + noise * (2 * rng.random() - 1))
            samples.append((n, p, s))
            out.append("sample %r %r %r" % (n, p, s))
    cols = [[1.0] * len(samples), [s[0] for s in samples], [s[0] * s[1] ** g for s in samples], [s[1] for s in samples]]
    coef, res = S.fit_costs(cols, [s[2] for s in samples])
    out.append("expect %s" % " ".join(repr(x) for x in coef))
open('scripts/tests/data/cost_fit_cases.txt', 'w').write("\n".join(out) + "\n")
