"""radius_schedule_numbers: every RMSE, slope and floor docs/findings-detp.md quotes for the radius
schedule and the floor against d is what the script prints from the committed tables.

Run: python3 -m unittest discover -s scripts/tests (from the repository root; .ci/run does).
"""

import contextlib
import io
import os
import re
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
import radius_schedule_numbers as R  # noqa: E402

ROOT = os.path.join(HERE, "..", "..")


def section():
    with open(os.path.join(ROOT, "docs", "findings-detp.md"), encoding="utf-8") as f:
        text = f.read()
    start = text.index("## A radius that shrinks with the photons")
    end = text.index("\n## ", start + 1)
    return text[start:end].replace("−", "-")


class RadiusScheduleNumbers(unittest.TestCase):
    def setUp(self):
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            R.main(["--results", os.path.join(ROOT, "results")])
            R.main(["--results", os.path.join(ROOT, "results"), "--floors"])
            R.main(["--results", os.path.join(ROOT, "results"), "--beta"])
            R.main(["--results", os.path.join(ROOT, "results"), "--crossings"])
        self.printed = out.getvalue()
        self.doc = section()

    def test_every_rmse_in_the_table_is_printed(self):
        """Each 'mean ± se' cell of the findings' table appears in the script's output."""
        cells = re.findall(r"0\.\d{5} ± 0\.\d{5}", self.doc)
        self.assertGreaterEqual(len(cells), 40)
        for c in cells:
            self.assertIn(c, self.printed)

    def test_the_floor_rule_is_judged_as_the_findings_say(self):
        """The verdict the spec's rule gives on the committed table is the one the findings state."""
        verdict = re.search(r"band \[1\.6, 2\.4\]: (\w+)", self.printed).group(1)
        self.assertIn("**%s** from the smooth field's 2" % verdict, self.doc)
        verdict = re.search(r"beta 0\.3: slope band \[-0\.25, -0\.15\]: (\w+)", self.printed).group(1)
        self.assertIn("(`detp-radius-beta-cornell`, %s)" % verdict, self.doc)

    def test_every_slope_and_interval_is_printed(self):
        """Each 'slope [lo, hi]' the findings quote is printed, to the digits the findings give."""
        quoted = re.findall(r"(-?0\.\d+) \[(-?0\.\d+), (-?0\.\d+)\]", self.doc)
        self.assertGreaterEqual(len(quoted), 14)
        printed = [tuple(float(x) for x in m) for m in
                   re.findall(r"(-?0\.\d+) \[(-?0\.\d+), (-?0\.\d+)\]", self.printed)]
        for q in quoted:
            digits = [len(x.split(".")[1]) for x in q]
            want = tuple(float(x) for x in q)
            self.assertTrue(any(all(abs(p - w) <= 0.5 * 10 ** -d + 1e-12 for p, w, d in zip(pp, want, digits))
                                for pp in printed), "not printed: %s" % (q,))


if __name__ == "__main__":
    unittest.main()
