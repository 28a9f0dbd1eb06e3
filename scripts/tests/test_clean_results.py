"""scripts/check_clean_results.py: a committed result from a dirty build fails CI unless it is on
the allow-list, and a listed result that is clean or gone fails too (the list cannot go stale).

Run: python3 -m unittest discover -s scripts/tests (from the repository root; .ci/run does).
"""

import os
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
import check_clean_results as C  # noqa: E402

CLEAN = '[raycost]\ngit_commit = "abc"\ngit_dirty = "false"\n'
DIRTY = '[raycost]\ngit_commit = "abc"\ngit_dirty = "true"\n'
DIRTY_INPUT = CLEAN + '[extra.fronts]\ngit_commit = "def"\ngit_dirty = "true"\n'


class CleanResults(unittest.TestCase):
    def run_check(self, metas, allowed):
        with tempfile.TemporaryDirectory() as root:
            results = os.path.join(root, "results")
            for rel, text in metas.items():
                p = os.path.join(root, rel)
                os.makedirs(os.path.dirname(p), exist_ok=True)
                with open(p, "w") as f:
                    f.write(text)
            allow = os.path.join(root, "allow.txt")
            with open(allow, "w") as f:
                f.write("# a comment\n\n" + "".join(a + "\n" for a in allowed))
            return C.problems(results, allow, root)

    def test_a_dirty_result_fails_unless_listed(self):
        metas = {"results/a/a.meta.toml": CLEAN, "results/b/crossover.meta.toml": DIRTY}
        errors, notes = self.run_check(metas, [])
        self.assertEqual(len(errors), 1)
        self.assertIn("results/b/crossover.meta.toml", errors[0])
        self.assertIn("raycost (commit abc)", errors[0])
        errors, notes = self.run_check(metas, ["results/b/crossover.meta.toml"])
        self.assertEqual((errors, len(notes)), ([], 1))

    def test_a_dirty_input_recorded_in_extra_counts(self):
        errors, _ = self.run_check({"results/c/runs/1/c.meta.toml": DIRTY_INPUT}, [])
        self.assertEqual(len(errors), 1)
        self.assertIn("extra.fronts (commit def)", errors[0])

    def test_a_listed_result_that_is_clean_or_gone_fails(self):
        errors, _ = self.run_check({"results/a/a.meta.toml": CLEAN},
                                   ["results/a/a.meta.toml", "results/z/z.meta.toml"])
        self.assertEqual(len(errors), 2)
        self.assertIn("is clean now", errors[0])
        self.assertIn("no longer exists", errors[1])

    def test_the_committed_results_pass(self):
        root = os.path.normpath(os.path.join(HERE, "..", ".."))
        errors, _ = C.problems(os.path.join(root, "results"),
                               os.path.join(root, ".ci", "known-dirty-results.txt"), root)
        self.assertEqual(errors, [])


if __name__ == "__main__":
    unittest.main()
