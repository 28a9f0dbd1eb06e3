"""detp_doc_numbers: every loose number docs/findings-detp.md and docs/reference.md quote from the
committed tables (covered points, the BART scenes' bias and RMSE ranges, points within d, the robots'
dark points, the predictor's run-to-run picks, the refined N* beside the head-to-head crossings) is what the script recomputes, phrase for phrase.

Run: python3 -m unittest discover -s scripts/tests (from the repository root; .ci/run does).
"""

import os
import re
import sys
import unittest

os.environ.setdefault("MPLBACKEND", "Agg")
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
import detp_doc_numbers as D  # noqa: E402

ROOT = os.path.join(HERE, "..", "..")


def flat(text):
    """Whitespace runs (line breaks included) as one space: prose wraps where it likes."""
    return re.sub(r"\s+", " ", text)


class DetpDocNumbers(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.quotes = D.quotes(os.path.join(ROOT, "results"))

    def test_every_phrase_is_in_its_doc(self):
        docs = {}
        for doc, phrase in self.quotes:
            if doc not in docs:
                with open(os.path.join(ROOT, "docs", doc), encoding="utf-8") as f:
                    docs[doc] = flat(f.read())
            self.assertIn(flat(phrase), docs[doc], "%s does not quote: %s" % (doc, phrase))

    def test_each_source_gives_its_phrases(self):
        """Nothing silently dropped: a table the script could not read would give fewer phrases."""
        self.assertEqual(len([q for d, q in self.quotes if d == "findings-detp.md"]), 15)
        self.assertEqual(len([q for d, q in self.quotes if d == "reference.md"]), 1)

    def test_a_changed_number_is_caught(self):
        """The comparison can fail: the covered points' phrase with another count is not in the findings."""
        with open(os.path.join(ROOT, "docs", "findings-detp.md"), encoding="utf-8") as f:
            text = flat(f.read())
        phrase = self.quotes[0][1]
        self.assertIn(phrase, text)
        changed = re.sub(r"^\d+", lambda m: str(int(m.group(0)) + 1), phrase)
        self.assertNotIn(changed, text)


if __name__ == "__main__":
    unittest.main()
