"""raycost_tables: tables are read back only through the columns their metadata declares.

Run: python3 -m unittest discover -s scripts/tests (from the repository root; .ci/run does).
"""

import glob
import gzip
import os
import shutil
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, ".."))
import raycost_tables as T  # noqa: E402

RESULTS = os.path.join(HERE, "..", "..", "results")

META = """[[columns.main]]
name = "point"
class = "parameter"
unit = "1"

[[columns.main]]
name = "n_i_mean"
class = "measured"
unit = "tests/ray"

[[columns.levels]]
name = "point"
class = "parameter"
unit = "1"

[[columns.levels]]
name = "level"
class = "parameter"
unit = "1"
"""


class Declared(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp()
        self.addCleanup(shutil.rmtree, self.dir)
        with open(os.path.join(self.dir, "exp.meta.toml"), "w") as f:
            f.write(META)

    def write(self, name, text):
        p = os.path.join(self.dir, name)
        with open(p, "w") as f:
            f.write(text)
        return p

    def test_a_declared_table_reads_with_its_units(self):
        p = self.write("exp.csv", "point,n_i_mean\n0,2.5\n1,3.5\n")
        header, rows = T.read_rows(p, float)
        self.assertEqual(header, ["point", "n_i_mean"])
        self.assertEqual([r["n_i_mean"] for r in rows], [2.5, 3.5])
        self.assertEqual(T.unit(p, "n_i_mean"), "tests/ray")
        self.assertEqual(T.column_class(p, "point"), "parameter")

    def test_a_side_table_is_its_own_declaration(self):
        p = self.write("exp.levels.csv", "point,level\n0,1\n")
        self.assertEqual(T.declaration(p)[1], "levels")
        self.assertEqual(T.read_rows(p, int)[1], [{"point": 0, "level": 1}])

    def test_an_undeclared_column_in_the_header_is_refused(self):
        p = self.write("exp.csv", "point,n_i_mean,extra\n0,2.5,1\n")
        with self.assertRaisesRegex(T.TableError, "undeclared: extra"):
            T.read_rows(p, float)

    def test_a_declared_column_missing_from_the_header_is_refused(self):
        p = self.write("exp.csv", "point\n0\n")
        with self.assertRaisesRegex(T.TableError, "declared but absent: n_i_mean"):
            T.read_rows(p, float)

    def test_a_reordered_header_is_refused(self):
        p = self.write("exp.csv", "n_i_mean,point\n2.5,0\n")
        with self.assertRaisesRegex(T.TableError, "order differs"):
            T.read_rows(p, float)

    def test_asking_for_an_undeclared_column_names_the_declared_ones(self):
        p = self.write("exp.csv", "point,n_i_mean\n0,2.5\n")
        with self.assertRaisesRegex(T.TableError, "n_s_mean not declared .*declared: point, n_i_mean"):
            T.read_rows(p, float, required=["n_s_mean"])
        with self.assertRaisesRegex(T.TableError, "not a declared column"):
            T.unit(p, "n_s_mean")

    def test_a_gzipped_table_is_read_when_only_it_exists(self):
        with gzip.open(os.path.join(self.dir, "exp.csv.gz"), "wt") as f:
            f.write("point,n_i_mean\n0,4.0\n")
        p = os.path.join(self.dir, "exp.csv")
        self.assertEqual(T.read_rows(p, float)[1][0]["n_i_mean"], 4.0)

    def test_a_named_table_in_a_folder_of_tables(self):
        with open(os.path.join(self.dir, "crossover.meta.toml"), "w") as f:
            f.write('[[columns.best]]\nname = "scene"\nclass = "parameter"\nunit = ""\n')
        p = self.write("best.csv", "scene\ncornell\n")
        self.assertEqual(T.declaration(p)[1], "best")
        with self.assertRaises(T.TableError):
            T.read_rows(self.write("best.csv", "scene,n_star\ncornell,1\n"), str)

    def test_a_table_without_metadata_reads_as_it_stands(self):
        d = tempfile.mkdtemp()
        self.addCleanup(shutil.rmtree, d)
        p = os.path.join(d, "hand.csv")
        with open(p, "w") as f:
            f.write("a,b\n1,2\n")
        self.assertIsNone(T.declaration(p))
        self.assertEqual(T.read_rows(p, int)[1], [{"a": 1, "b": 2}])


class Committed(unittest.TestCase):
    def test_every_committed_table_with_metadata_matches_its_declaration(self):
        tables = sorted(glob.glob(os.path.join(RESULTS, "**", "*.csv"), recursive=True)
                        + glob.glob(os.path.join(RESULTS, "**", "*.csv.gz"), recursive=True))
        declared = 0
        for p in tables:
            if T.declaration(p) is not None:
                T.read_rows(p, str)
                declared += 1
        self.assertGreater(declared, 100)


if __name__ == "__main__":
    unittest.main()
