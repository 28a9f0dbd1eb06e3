"""Writes percentile_cases.txt: the bootstrap's percentile convention, held equal in Python
(raycost_stats.percentile) and Rust (stats::percentile) on shared cases. The convention: of n sorted
values, the q-quantile is the value at 0-based rank floor(q·(n − 1)) computed in IEEE double
arithmetic (numpy's 'lower' method). Cases: the draw counts the bootstrap uses at the levels it uses,
the ends, tiny n, and products that round across an integer in double (0.29·100 → 28.999…).
Run from the repository root: python3 scripts/tests/data/make_percentile_cases.py"""
import math

cases = []
for n in (1, 2, 3, 4, 5, 10, 11, 101, 1000, 2000, 4000, 4001):
    for level in (0.5, 0.9, 0.95, 0.99):
        a = (1.0 - level) / 2.0
        cases += [(n, a), (n, 1.0 - a), (n, 0.5 - 0.5 * level), (n, 0.5 + 0.5 * level)]
    cases += [(n, 0.0), (n, 1.0), (n, 0.5)]
cases += [(101, 0.29), (11, 0.7), (101, 0.57), (1001, 0.001)]
out = ["# The bootstrap's percentile convention, shared by Python (raycost_stats.percentile) and Rust",
       "# (stats::percentile): of n sorted values the q-quantile is the one at 0-based rank",
       "# floor(q·(n − 1)) in IEEE double. Written by make_percentile_cases.py; each line: N Q RANK",
       "# (Q as Python's repr, read back exactly by both)."]
seen = set()
for n, q in cases:
    if (n, q) in seen:
        continue
    seen.add((n, q))
    out.append("%d %r %d" % (n, q, math.floor(q * (n - 1))))
open("scripts/tests/data/percentile_cases.txt", "w").write("\n".join(out) + "\n")
