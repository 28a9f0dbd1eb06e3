"""nstar_by_rule: each crossover row is labelled by its method, direct light, edge remedy and radius
rule (κ and the schedule together where both are set), and shows N* [lo, hi] or the reason it is
not finite.

Run: python3 -m unittest discover -s scripts/tests (from the repository root; .ci/run does).
"""

import contextlib
import io
import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
import nstar_by_rule as N  # noqa: E402

HEADER = ",".join(N.COLUMNS + ("photons_measured_max",))
ROWS = [
    "cornell,0.1,sphere-cache,photons,paper,1.6e6,0.01,15.0,NaN,0.0,6600.0,5250.0,7020.0,0.0,,8e5",
    "cornell,0.1,sphere-cache,nee,clamp-first-hit,NaN,NaN,15.0,0.5,0.16666666666666666,inf,NaN,NaN,1.0,a floor appears,8e5",
    "cornell,0.05,photon-map,nee,NaN,4e5,0.2,NaN,NaN,NaN,1020.0,615.0,1080.0,0.25,,8e5",
    "cornell,0.05,disc-index,photons,paper,NaN,0.07,15.0,NaN,0.0,inf,NaN,NaN,1.0,error floor,8e5",
]


class NstarByRule(unittest.TestCase):
    def printed(self, *flags):
        """What the script prints for a crossover folder holding ROWS."""
        with tempfile.TemporaryDirectory() as d:
            with open(os.path.join(d, "crossover.csv"), "w", encoding="utf-8") as f:
                f.write(HEADER + "\n" + "\n".join(ROWS) + "\n")
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                self.assertEqual(N.main(list(flags) + [d]), 0)
        return out.getvalue().splitlines()

    def test_labels_cells_and_targets(self):
        text = self.printed()
        self.assertEqual(text[1], "target 0.1:")
        fixed = [l for l in text if "edge=paper" in l][0]
        self.assertIn("d=15 d fixed", fixed)
        self.assertIn("6.6e+03 [5.25e+03, 7.02e+03] never 0.00 (N_eps 1.6e+06, 2× past", fixed)
        both = [l for l in text if "kappa" in l][0]
        self.assertIn("kappa=0.5 schedule beta=0.167", both)
        self.assertIn("never: a floor appears", both)
        self.assertLess(text.index(both), text.index("target 0.05:"))
        m = [l for l in text if "photon-map" in l][0]
        self.assertNotIn("edge=", m)
        self.assertTrue(m.endswith("1.02e+03 [615, 1.08e+03] never 0.25"), m)

    def test_best_keeps_the_smallest_n_star_per_rule_or_says_never(self):
        text = self.printed("--best")
        self.assertEqual(len(text), 4, text)
        self.assertTrue(text[1].startswith("0.1 d fixed          sphere-cache direct=photons"), text)
        self.assertEqual(text[2], "0.1 kappa + schedule never (a floor appears)")
        self.assertEqual(text[3], "0.05 d fixed          never (error floor)")

    def test_a_missing_folder_is_an_error(self):
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            self.assertEqual(N.main(["/nonexistent/x"]), 2)
        self.assertIn("no such file", err.getvalue())


ROOT = os.path.join(HERE, "..", "..")


class FindingsBlock(unittest.TestCase):
    """docs/findings-detp.md quotes `nstar_by_rule.py --best` over the committed crossovers: the
    block is the script's output, line for line."""

    def test_the_block_is_what_the_script_prints(self):
        with open(os.path.join(ROOT, "docs", "findings-detp.md"), encoding="utf-8") as f:
            text = f.read()
        begin = text.index("<!-- nstar_by_rule --best: begin -->")
        end = text.index("<!-- nstar_by_rule --best: end -->")
        block = [l for l in text[begin:end].splitlines()[1:] if l and not l.startswith("```")]
        folders = [l.split()[1] for l in block if l.startswith("## ")]
        self.assertGreaterEqual(len(folders), 1, block)
        out = io.StringIO()
        cwd = os.getcwd()
        try:
            os.chdir(ROOT)
            with contextlib.redirect_stdout(out):
                self.assertEqual(N.main(["--best"] + folders), 0)
        finally:
            os.chdir(cwd)
        self.assertEqual(block, out.getvalue().splitlines())


if __name__ == "__main__":
    unittest.main()
