"""scripts/check_rerunnable_results.py: a committed result that `raycost reproduce --check` refuses
fails CI unless it is on the allow-list, and a listed result that is rerunnable now or gone fails too
(the list only shrinks). A stand-in for raycost refuses every folder whose path holds "stale".

Run: python3 -m unittest discover -s scripts/tests (from the repository root; .ci/run does).
"""

import os
import stat
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
import check_rerunnable_results as R  # noqa: E402

FAKE = '#!/bin/sh\ncase "$2" in *stale*) echo "error: spec hash changed" >&2; exit 2;; esac\necho rerunnable\n'
RUN = '[run]\ncommand = "run"\n'


class RerunnableResults(unittest.TestCase):
    def run_check(self, metas, allowed):
        with tempfile.TemporaryDirectory() as root:
            for rel, text in metas.items():
                p = os.path.join(root, rel)
                os.makedirs(os.path.dirname(p), exist_ok=True)
                with open(p, "w") as f:
                    f.write(text)
            fake = os.path.join(root, "raycost")
            with open(fake, "w") as f:
                f.write(FAKE)
            os.chmod(fake, os.stat(fake).st_mode | stat.S_IEXEC)
            allow = os.path.join(root, "allow.txt")
            with open(allow, "w") as f:
                f.write("# a comment\n\n" + "".join(a + "\n" for a in allowed))
            return R.problems(fake, os.path.join(root, "results"), allow, root)

    def test_a_refused_result_fails_unless_listed(self):
        metas = {"results/a/a.meta.toml": RUN, "results/stale-b/b.meta.toml": RUN,
                 "results/bench/bench.meta.toml": '[run]\ncommand = "bench"\n'}
        errors, stale, folders = self.run_check(metas, [])
        self.assertEqual(folders, ["results/a", "results/stale-b"], "bench is not rerunnable: skipped")
        self.assertEqual(len(errors), 1)
        self.assertIn("results/stale-b: cannot be rerun", errors[0])
        errors, stale, _ = self.run_check(metas, ["results/stale-b/"])
        self.assertEqual(errors, [])
        self.assertEqual(len(stale), 1)
        self.assertTrue(stale[0].startswith("results/stale-b: cannot be rerun"), stale)

    def test_a_listed_result_that_reruns_or_is_gone_fails(self):
        metas = {"results/a/a.meta.toml": RUN, "results/a/runs/0/a.meta.toml": RUN}
        errors, _, folders = self.run_check(metas, ["results/a/runs/0", "results/gone"])
        self.assertEqual(folders, ["results/a", "results/a/runs/0"])
        self.assertEqual(len(errors), 2, errors)
        self.assertIn("rerunnable now", errors[0])
        self.assertIn("no longer exists", errors[1])


if __name__ == "__main__":
    unittest.main()
