"""The findings documents agree with the recorded verdicts.

docs/findings-*.md state verdicts in prose. A line that states one carries the claim's id in an
HTML comment, `<!-- claim: ID -->` (invisible on the page); every verdict word on that line —
holds, holds in part, differs, refuted, inconclusive (and their inflections) — must be the outcome
results/claims.toml records for that claim, a rule id named on it (`ID/N`) must be the claim's
current rule, and the id must exist. A test fails on any disagreement, so a rerun that changes a
verdict cannot leave the prose behind.

Run: python3 -m unittest discover -s scripts/tests (from the repository root; .ci/run does).
"""

import glob
import os
import re
import tomllib
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
FINDINGS = sorted(glob.glob(os.path.join(ROOT, "docs", "findings-*.md")))

MARK = re.compile(r"<!-- claim: ([A-Za-z0-9-]+) -->")
# A verdict word and what it says; "hold(s) in part" before "hold(s)", a negation ("does not
# hold") says the claim fails, which only differs or refuted can mean.
WORD = re.compile(r"(\bnot |n't )?\b(?:(holds?|holding)([- ]in[- ]part)?|(refuted|differs|inconclusive))\b")
OUTCOMES = ("holds", "holds-in-part", "differs", "refuted", "inconclusive")


def said(match):
    """The outcomes a verdict word agrees with."""
    negated, hold, part, other = match.groups()
    if other:
        return {other}
    if part:
        return {"holds-in-part"}
    return {"differs", "refuted"} if negated else {"holds"}


def committed_claims(path=os.path.join(ROOT, "results", "claims.toml")):
    """{claim id: its record} of results/claims.toml (the id is its rule's head)."""
    with open(path, "rb") as f:
        return {c["rule"].split("/")[0]: c for c in tomllib.load(f)["claim"]}


def marked_lines(text):
    """(line number, claim id, the line without its markers) for every marked line."""
    out = []
    for n, line in enumerate(text.splitlines(), 1):
        for m in MARK.finditer(line):
            out.append((n, m.group(1), MARK.sub("", line)))
    return out


def disagreements(text, by_id, name="findings"):
    """Every marked line whose claim does not exist, that states no verdict, whose verdict words
    are not the recorded outcome, or that names another rule of the claim than the current one;
    and every unmarked line that says Theorem 2 holds (the verdict that went stale once)."""
    out = []
    for n, cid, line in marked_lines(text):
        where = "%s:%d: %s" % (name, n, cid)
        c = by_id.get(cid)
        if c is None:
            out.append("%s: no such claim in results/claims.toml" % where)
            continue
        words = list(WORD.finditer(line))
        if not words:
            out.append("%s: the marked line states no verdict: %r" % (where, line.strip()))
        for w in words:
            if c["outcome"] not in said(w):
                out.append("%s: the line says %r, results/claims.toml records %s under %s: %r" % (
                    where, w.group(0), c["outcome"], c["rule"], line.strip()))
        for rule in re.findall(r"\b%s/\d+\b" % re.escape(cid), line):
            if rule != c["rule"]:
                out.append("%s: names rule %s, the claim's rule is %s" % (where, rule, c["rule"]))
    for n, line in enumerate(text.splitlines(), 1):
        if not MARK.search(line) and re.search(r"Theorem 2[^.]*\bholds\b|\bholds in seconds\b", line):
            out.append("%s:%d: a verdict on an unmarked line: %r" % (name, n, line.strip()))
    return out


class FindingsAgreeWithTheVerdicts(unittest.TestCase):
    def test_every_marked_verdict_is_the_recorded_one(self):
        by_id = committed_claims()
        problems, marked = [], set()
        for path in FINDINGS:
            with open(path) as f:
                text = f.read()
            problems += disagreements(text, by_id, os.path.relpath(path, ROOT))
            marked |= {cid for _, cid, _ in marked_lines(text)}
        self.assertEqual(problems, [])
        # Both papers' findings state verdicts: at least the Theorem 2 claims and the grid's.
        self.assertGreaterEqual(len(marked), 20, sorted(marked))

    def test_the_outcome_words_are_the_engines(self):
        import sys
        sys.path.insert(0, os.path.join(ROOT, "scripts"))
        import claims_rules
        self.assertEqual(tuple(OUTCOMES), tuple(claims_rules.OUTCOMES))

    def test_a_stale_or_unknown_verdict_is_caught(self):
        by_id = {"theorem-2": {"outcome": "differs", "rule": "theorem-2/2"},
                 "figure-10": {"outcome": "holds-in-part", "rule": "figure-10/2"}}
        ok = "- theorem-2 (rule theorem-2/2): **differs** <!-- claim: theorem-2 -->\n"
        self.assertEqual(disagreements(ok, by_id), [])
        for bad in ["- theorem-2 (rule theorem-2/2): **holds** <!-- claim: theorem-2 -->\n",
                    "- theorem-2 (rule theorem-2/1): **differs** <!-- claim: theorem-2 -->\n",
                    "- Theorem 2 **differs**, and inconclusive beside <!-- claim: theorem-2 -->\n",
                    "- no verdict word here <!-- claim: theorem-2 -->\n",
                    "- it differs <!-- claim: theorem-3 -->\n",
                    ok + "the theorem holds in seconds here\n"]:
            self.assertEqual(len(disagreements(bad, by_id)), 1, bad)
        # In part is its own outcome; "holds" alone is not it, nor is it "holds".
        self.assertEqual(disagreements("Figure 10 holds in part <!-- claim: figure-10 -->", by_id), [])
        self.assertEqual(disagreements("Figure 10 hold-in-part <!-- claim: figure-10 -->", by_id), [])
        self.assertEqual(len(disagreements("Figure 10 holds <!-- claim: figure-10 -->", by_id)), 1)
        # A negated hold agrees with differs, not with holds.
        self.assertEqual(disagreements("it does not hold <!-- claim: theorem-2 -->", by_id), [])


if __name__ == "__main__":
    unittest.main()
