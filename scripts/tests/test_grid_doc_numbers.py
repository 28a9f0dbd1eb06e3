"""grid_doc_numbers: the numbers docs/findings-grid.md quotes come from the committed tables.

Run: python3 -m unittest discover -s scripts/tests (from the repository root; .ci/run does).
"""

import contextlib
import io
import os
import re
import sys
import tomllib
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
import grid_doc_numbers as G  # noqa: E402

RESULTS = os.path.join(HERE, "..", "..", "results")


class GridDocNumbers(unittest.TestCase):
    def test_runs_on_the_committed_tables(self):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            self.assertEqual(G.main(["--results", RESULTS]), 0)
        for name in G.GRID:
            self.assertIn("== " + name, out.getvalue())

    def test_first_hit_mean_agrees_with_the_claims_engine(self):
        """Σz² of t* over grid-cell-width, as printed for the docs, is the claims engine's figure."""
        with open(os.path.join(RESULTS, "claims.toml"), "rb") as f:
            claims = tomllib.load(f)["claim"]
        measured = next(c["measured"] for c in claims if c["rule"].startswith("first-hit-mean/"))
        q_claims = float(re.search(r"Σz² = ([0-9.]+)", measured).group(1))
        q, _, _ = G.zscores(G.rows_of(RESULTS, "grid-cell-width"), "t_hit")
        self.assertAlmostEqual(q, q_claims, delta=0.05)

    def test_a_missing_table_is_exit_2(self):
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            self.assertEqual(G.main(["--results", os.path.join(HERE, "no-such-folder")]), 2)


if __name__ == "__main__":
    unittest.main()
