"""README's claims table and docs/claims.md: one short line a claim, every claim present, and both
exactly what scripts/claims.py renders from the committed results/claims.toml — checked without
judging anything (`python3 scripts/claims.py --check` judges the tables again; this is the fast
check that the documents follow the file).

Run: python3 -m unittest discover -s scripts/tests (from the repository root; .ci/run does).
"""

import os
import re
import sys
import tomllib
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import claims  # noqa: E402

PREREG = os.path.join(ROOT, "claims", "preregistered.toml")
CLAIMS = os.path.join(ROOT, "results", "claims.toml")
README = os.path.join(ROOT, "README.md")
MAX_ROW = 640  # characters a README claims row may take: a reader scans it, the units are in the doc


def read(path):
    with open(path) as f:
        return f.read()


def table_block(readme):
    """The text between README's claims markers."""
    return readme.split(claims.BEGIN, 1)[1].split(claims.END, 1)[0].strip("\n")


def table_problems(block, ids, max_row=MAX_ROW):
    """Every row wider than max_row, every claim id without exactly one row linking to its section
    of the doc, and every row that links to no claim."""
    rows = block.splitlines()[2:]
    out = ["row %d is %d characters (at most %d): %s…" % (i + 1, len(r), max_row, r[:80])
           for i, r in enumerate(rows) if len(r) > max_row]
    linked = [m.group(1) for r in rows for m in [re.search(re.escape(claims.DOC) + r"#([a-z0-9-]+)\)", r)] if m]
    out += ["claim %s has %d rows" % (i, linked.count(i)) for i in ids if linked.count(i) != 1]
    out += ["a row links to %s, not a claim" % i for i in linked if i not in ids]
    if len(linked) != len(rows):
        out.append("%d rows link to no claim's section" % (len(rows) - len(linked)))
    return out


class ClaimsDocuments(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.pre = claims.load(PREREG)
        cls.ids = [c["id"] for c in cls.pre["claim"]]
        cls.records = claims.records_of(CLAIMS, cls.pre)

    def test_the_readme_table_is_one_short_line_a_claim(self):
        self.assertEqual(table_problems(table_block(read(README)), self.ids), [])

    def test_the_readme_table_is_rendered_from_the_committed_file(self):
        self.assertEqual(table_block(read(README)), claims.render_table(self.records))

    def test_the_doc_is_current(self):
        self.assertEqual(read(os.path.join(ROOT, claims.DOC)), claims.render_doc(self.records))

    def test_the_doc_has_every_unit_of_every_claim(self):
        doc = read(os.path.join(ROOT, claims.DOC))
        for r in self.records:
            self.assertIn("\n## %s\n" % r["id"], doc)
            self.assertIn("Every unit (%d):" % len(r["units"]), doc)
        # The file records every unit: more than the measured text lists where a claim has many.
        many = [r for r in self.records if len(r["units"]) > claims.UNITS_LISTED]
        self.assertTrue(many)

    def test_the_records_read_back_are_the_file(self):
        with open(CLAIMS, "rb") as f:
            engine = tomllib.load(f)["engine"]
        self.assertEqual(read(CLAIMS), claims.render_toml(self.records, engine))

    def test_every_claim_has_a_headline(self):
        for r in self.records:
            self.assertTrue(r["headline"], r["id"])
            self.assertLess(len(r["headline"]), len(r["measured"]) + 1, r["id"])

    def test_a_long_row_or_a_missing_claim_fails(self):
        row = "| [x](%s#a) (p) | 1 | 2 | **holds** | [t](results/t/t.csv) |" % claims.DOC
        head = "| h |\n|---|\n"
        self.assertEqual(table_problems(head + row, ["a"]), [])
        self.assertEqual(len(table_problems(head + row, ["a"], max_row=len(row) - 1)), 1)
        self.assertEqual(len(table_problems(head + row, ["a", "b"])), 1)
        self.assertEqual(len(table_problems(head + row + "\n" + row, ["a"])), 1)
        self.assertEqual(len(table_problems(head + row.replace("#a", "#c"), ["a"])), 2)


if __name__ == "__main__":
    unittest.main()
