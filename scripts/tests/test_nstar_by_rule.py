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

    def test_markdown_is_one_row_per_target_with_a_cell_per_rule(self):
        text = self.printed("--markdown")
        self.assertEqual(len(text), 4, text)
        self.assertTrue(text[0].startswith("| scene | ε | d fixed | κ = 0.5 |"), text)
        cells = [c.strip() for c in text[2].strip("|").split("|")]
        self.assertEqual(cells[:2], ["cornell", "10 %"])
        self.assertEqual(cells[2], "**6.6·10³** [5.2·10³, 7·10³]: sphere cache, photons, paper's "
                                   "edge (N_ε 2× the data)")
        self.assertEqual(cells[3], "–")  # no κ-only row at 10 %
        self.assertEqual(cells[5], "never: a floor appears")  # a reason kept as written
        self.assertEqual([c.strip() for c in text[3].strip("|").split("|")][2:],
                         ["never: error floor", "–", "–", "–"])

    def test_numbers_and_ratios_as_the_readme_writes_them(self):
        self.assertEqual([N.sci(x) for x in (1640.0, 9.96e4, 3.5e10, 0.0, float("inf"))],
                         ["1.6·10³", "1·10⁵", "3.5·10¹⁰", "0", "∞"])
        self.assertEqual([N.times(x) for x in (1.09, 43.7, 1094.0, 88700.0)],
                         ["1.1×", "44×", "1 100×", "89 000×"])

    def test_a_missing_folder_is_an_error(self):
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            self.assertEqual(N.main(["/nonexistent/x"]), 2)
        self.assertIn("no such file", err.getvalue())


ROOT = os.path.join(HERE, "..", "..")


def quoted_block(path, flag):
    """The lines between `<!-- nstar_by_rule FLAG: begin -->` and its end marker in PATH (code
    fences and blank lines left out), and the folders named by the marker's `folders:` line or by
    the block's `## FOLDER` headings."""
    with open(os.path.join(ROOT, path), encoding="utf-8") as f:
        text = f.read()
    begin = text.index("<!-- nstar_by_rule %s: begin" % flag)
    end = text.index("<!-- nstar_by_rule %s: end -->" % flag)
    head, _, body = text[begin:end].partition("-->")
    block = [l for l in body.splitlines() if l and not l.startswith("```")]
    folders = head.split("folders:")[1].split() if "folders:" in head else [
        l.split()[1] for l in block if l.startswith("## ")]
    return block, folders


def printed_at_root(args):
    """What the script prints, run from the repository root."""
    out = io.StringIO()
    cwd = os.getcwd()
    try:
        os.chdir(ROOT)
        with contextlib.redirect_stdout(out):
            status = N.main(args)
    finally:
        os.chdir(cwd)
    return status, out.getvalue().splitlines()


class QuotedBlocks(unittest.TestCase):
    """docs/findings-detp.md quotes `nstar_by_rule.py --best` and README.md `--markdown` over the
    committed crossovers: each block is the script's output, line for line."""

    def check(self, path, flag):
        block, folders = quoted_block(path, flag)
        self.assertGreaterEqual(len(folders), 1, block)
        status, out = printed_at_root([flag] + folders)
        self.assertEqual(status, 0)
        self.assertEqual(block, out)

    def test_the_findings_block_is_what_the_script_prints(self):
        self.check(os.path.join("docs", "findings-detp.md"), "--best")

    def test_the_readme_table_is_what_the_script_prints(self):
        self.check("README.md", "--markdown")


if __name__ == "__main__":
    unittest.main()
