"""Reading raycost's result tables back through the columns their metadata declares.

raycost writes, beside every table, a NAME.meta.toml whose [columns.TABLE] lists each column of
each table it wrote: its name, its class (parameter, measured, theory, …) and its unit, in the
order of the header. The Rust side checks a table against those declarations before it reads one
back (resume, merge, crossover); this module is the same check for the Python side, so the plots
and the claims engine read a column only if the run that wrote the table declared it:

- a table with metadata must have exactly the declared header (same names, same order); a table
  edited by hand, cut short at the header, or paired with another run's metadata is refused;
- asking for a column the table does not declare is refused with the declared names listed, so a
  renamed column fails loudly instead of reading as missing data;
- `unit(path, column)` and `column_class(path, column)` give what the declaration says.

Which metadata belongs to a table: NAME.csv is table `main` of NAME.meta.toml and NAME.SIDE.csv
is table SIDE of it; a command that writes several named tables into one folder (`raycost
crossover`: crossover.csv, best.csv, … with crossover.meta.toml) declares each by its file stem.
A table without metadata (an old result, a hand-made CSV) is read with its header as it stands.
Tables over 5 MiB are committed gzipped: PATH.gz is read when PATH is absent.
"""

import csv
import glob
import gzip
import os
import tomllib


class TableError(Exception):
    """A table that cannot be read as declared (missing, empty, header unlike its declaration)."""


def table_file(path):
    """PATH, or PATH.gz when only the compressed table exists."""
    if not os.path.exists(path) and os.path.exists(path + ".gz"):
        return path + ".gz"
    return path


def _plain(path):
    return path[:-3] if path.endswith(".gz") else path


def _load(meta):
    with open(meta, "rb") as f:
        return tomllib.load(f).get("columns") or {}


def declaration(path):
    """(meta path, table name, [{name, class, unit}]) for the table at PATH, or None when no
    metadata beside it declares it."""
    plain = _plain(path)
    folder, file = os.path.split(plain)
    stem = file[:-4] if file.endswith(".csv") else file
    parts = stem.split(".")
    # NAME.csv -> (NAME, main); NAME.SIDE.csv -> (NAME, SIDE); names may themselves hold dots.
    for cut in range(len(parts), 0, -1):
        name, table = ".".join(parts[:cut]), ".".join(parts[cut:]) or "main"
        meta = os.path.join(folder, name + ".meta.toml")
        if os.path.exists(meta):
            cols = _load(meta)
            if table in cols:
                return meta, table, cols[table]
    # A folder of named tables under one metadata file: the table is the file's stem.
    for meta in sorted(glob.glob(os.path.join(folder, "*.meta.toml"))):
        cols = _load(meta)
        if stem in cols:
            return meta, stem, cols[stem]
    return None


def declared_names(path):
    """The declared column names of the table at PATH in header order (None without metadata)."""
    d = declaration(path)
    return None if d is None else [c["name"] for c in d[2]]


def _column(path, name):
    d = declaration(path)
    if d is None:
        raise TableError("%s: no metadata declares this table's columns" % path)
    for c in d[2]:
        if c["name"] == name:
            return c
    raise TableError("%s: %s is not a declared column (declared in %s: %s)"
                     % (path, name, d[0], ", ".join(c["name"] for c in d[2])))


def unit(path, name):
    """The unit the metadata declares for column NAME of the table at PATH."""
    return _column(path, name).get("unit", "")


def column_class(path, name):
    """The class (parameter, measured, theory, …) declared for column NAME of the table at PATH."""
    return _column(path, name).get("class", "")


def check_header(path, header, required=()):
    """Fail (TableError) when HEADER differs from the declared columns or lacks a REQUIRED one."""
    header = list(header)
    d = declaration(path)
    if d is not None:
        names = [c["name"] for c in d[2]]
        if header != names:
            extra = [h for h in header if h not in names]
            absent = [n for n in names if n not in header]
            what = []
            if extra:
                what.append("undeclared: " + ", ".join(extra))
            if absent:
                what.append("declared but absent: " + ", ".join(absent))
            raise TableError("%s: the header is not the columns %s declares for table %s (%s)"
                             % (path, d[0], d[1], "; ".join(what) or "the order differs"))
        undeclared = [c for c in required if c not in names]
        if undeclared:
            raise TableError("%s: %s not declared for table %s in %s (declared: %s)"
                             % (path, ", ".join(undeclared), d[1], d[0], ", ".join(names)))
    missing = [c for c in required if c not in header]
    if missing:
        raise TableError("%s: missing required column%s %s (present: %s)"
                         % (path, "s" if len(missing) > 1 else "", ", ".join(missing), ", ".join(header)))


def read_rows(path, convert, required=()):
    """(header, rows as dicts with every cell passed through CONVERT) of the table at PATH (or
    PATH.gz), its header checked against its declaration and REQUIRED."""
    real = table_file(path)
    if not os.path.exists(real):
        raise TableError("%s: no such file" % path)
    opener = gzip.open(real, "rt", newline="") if real.endswith(".gz") else open(real, newline="")
    with opener as f:
        reader = csv.DictReader(f)
        header = list(reader.fieldnames or [])
        if not header:
            raise TableError("%s: empty file" % path)
        check_header(path, header, required)
        rows = [{k: convert(v) for k, v in row.items()} for row in reader]
    return header, rows
