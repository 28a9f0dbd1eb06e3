"""scripts/compare_tables.py brings old tables up to date with the list `raycost reproduce` uses
(src/output/header_changes.toml), with the same meaning: a rename, a dropped duplicate checked row
by row."""

import os
import sys
import tempfile
import unittest
from pathlib import Path

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
import compare_tables as C  # noqa: E402

RENAME = {"kind": "detp", "table": "main", "old": "rays_per_s", "renamed": "segments_per_s", "why": "w"}
DROP = {"kind": "quasi-static", "table": "main", "old": "photons", "duplicate_of": "detp.photons", "why": "w"}


class Upgrade(unittest.TestCase):
    def test_a_renamed_column_takes_its_new_name_in_the_header_and_the_classes(self):
        h, rows, cls, applied, diff = C.upgrade([RENAME], ["point", "rays_per_s"], [["0", "1e6"]],
                                                [("point", "parameter"), ("rays_per_s", "timing")])
        self.assertEqual(h, ["point", "segments_per_s"])
        self.assertEqual(rows, [["0", "1e6"]])
        self.assertEqual(cls, [("point", "parameter"), ("segments_per_s", "timing")])
        self.assertEqual((len(applied), diff), (1, []))

    def test_a_rename_to_a_name_already_present_is_a_difference(self):
        _, _, _, applied, diff = C.upgrade([RENAME], ["rays_per_s", "segments_per_s"], [["1", "2"]], [])
        self.assertEqual(applied, [])
        self.assertEqual(len(diff), 1)

    def test_a_dropped_duplicate_is_removed_and_a_row_where_it_differed_is_reported(self):
        header = ["point", "detp.photons", "photons", "segments"]
        rows = [["0", "100", "100", "7"], ["1", "200", "300", "9"]]
        h, rows, cls, applied, diff = C.upgrade([DROP], header, rows, [(c, "parameter") for c in header])
        self.assertEqual(h, ["point", "detp.photons", "segments"])
        self.assertEqual(rows[1], ["1", "200", "9"])
        self.assertEqual(len(cls), 3)
        self.assertEqual(len(applied), 1)
        self.assertEqual(len(diff), 1)
        self.assertTrue(diff[0].startswith("row 1: photons"), diff)

    def test_a_table_without_the_old_column_is_left_alone(self):
        h, rows, _, applied, diff = C.upgrade([RENAME, DROP], ["point"], [["0"]], [])
        self.assertEqual((h, rows, applied, diff), (["point"], [["0"]], [], []))


class TheList(unittest.TestCase):
    def test_the_committed_list_reads_and_selects_by_kind_and_table(self):
        detp = C.header_changes("detp", "main")
        self.assertTrue(any(c["old"] == "rays_per_s" for c in detp))
        self.assertTrue(all(c["kind"] == "detp" and c["table"] == "main" for c in detp))
        self.assertEqual(C.header_changes("grid", "main"), [])

    def test_an_entry_with_both_or_neither_change_is_refused(self):
        with tempfile.TemporaryDirectory() as d:
            p = Path(d) / "l.toml"
            p.write_text('[[change]]\nkind = "k"\ntable = "main"\nold = "a"\nwhy = "w"\n')
            with self.assertRaises(SystemExit):
                C.header_changes("k", "main", p)

    def test_an_old_table_compares_equal_to_its_renamed_rerun(self):
        with tempfile.TemporaryDirectory() as d:
            old, new = Path(d) / "old.csv", Path(d) / "new.csv"
            old.write_text("point,rays_per_s,segments\n0,5,7\n")
            new.write_text("point,segments_per_s,segments\n0,6,7\n")
            cls = [("point", "parameter"), ("rays_per_s", "timing"), ("segments", "measured")]
            new_cls = [("point", "parameter"), ("segments_per_s", "timing"), ("segments", "measured")]
            ok, line = C.compare_table("t", old, new, cls, new_cls, (), [RENAME])
            self.assertTrue(ok, line)
            self.assertIn("mapped: rays_per_s read as segments_per_s", line)
            ok, line = C.compare_table("t", old, new, cls, new_cls, (), [])
            self.assertFalse(ok, line)


if __name__ == "__main__":
    unittest.main()
