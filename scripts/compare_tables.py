#!/usr/bin/env python3
"""Compare the result tables of two result folders, column class by column class.

    python3 scripts/compare_tables.py OLD_DIR NEW_DIR

Both folders hold experiment folders (`NAME/NAME.csv`, `NAME/NAME.TABLE.csv`, `NAME/NAME.meta.toml`),
as `raycost run --out DIR` writes them. For every table of every experiment in OLD_DIR, the same
table must exist in NEW_DIR with the same header (names and order) and the same classes in its
metadata; every column that is not of class `timing` (read from `[[columns.TABLE]]` of each table's
`NAME.meta.toml`) must be equal byte for byte in every row. Timing columns (seconds, rates and what
a clock decided) are the only ones allowed to differ between two runs of one spec and seed.

`--added COLUMN` (repeatable) names a column the new binary adds (a new parameter): it may appear in
the new tables only, and is left out before the headers are compared; `--added TABLE:COLUMN` only in
that side table (`frames:static_index_build_s`), `main:COLUMN` only in the main table.

Columns a kind renamed or stopped writing since the old tables were written are brought up to date
on the old side first, from the list `raycost reproduce` uses (src/output/header_changes.toml): a
renamed column is read under its new name; a dropped duplicate must equal the column it repeated,
row by row (else each differing row is a difference), and is then left out. Each is printed.

Prints one line per table: "N measured columns of M compared, 0 differ", or the first differences;
exits 1 on any difference (or a missing table), 0 otherwise.

`--stream-changed Z` compares two binaries whose random streams differ (every measured cell moves):
parameter columns of the main tables must still be equal (side tables whose rows follow the data —
levels, histogram bins — are skipped when their keys move), and every measured `X_mean` with its
`X_se` in both tables must agree within Z combined standard errors (|a − b| / √(se_a² + se_b²) ≤ Z); other measured and
theory cells are only counted. The largest such z per table is printed. An SE from few clusters is
itself noisy (two replicas give an SE from two values), so a z above Z is a lead to rerun with
more replicas, not a verdict; read it with the table's `X_clusters`. To show that nothing but the
streams changed, build with the old streams instead and compare byte for byte (scripts/parity_runs.sh).
"""

import argparse
import csv
import math
import sys
import tomllib
from pathlib import Path

# Differences printed per table before the rest are only counted.
SHOWN = 5

HEADER_CHANGES = Path(__file__).resolve().parent.parent / "src" / "output" / "header_changes.toml"


def header_changes(kind, table, path=HEADER_CHANGES):
    """The changes of src/output/header_changes.toml that apply to `kind`'s `table`, oldest first."""
    changes = tomllib.loads(path.read_text())["change"]
    for c in changes:
        if ("renamed" in c) == ("duplicate_of" in c):
            raise SystemExit(f"error: {path}: {c.get('old')}: give exactly one of renamed and duplicate_of")
    return [c for c in changes if c["kind"] == kind and c["table"] == table]


def upgrade(changes, header, rows, cls):
    """Brings an old table up to date (the list's meaning, as `raycost reproduce` applies it):
    returns (header, rows, classes, lines applied, differences)."""
    applied, differences = [], []
    for c in changes:
        if c["old"] not in header:
            continue
        at = header.index(c["old"])
        if "renamed" in c:
            new = c["renamed"]
            if new in header:
                differences.append(f"both {c['old']} and its new name {new} in one header")
                continue
            header = header[:at] + [new] + header[at + 1:]
            cls = [(new if n == c["old"] else n, k) for n, k in cls]
            applied.append(f"{c['old']} read as {new} ({c['why']})")
            continue
        kept = c["duplicate_of"]
        if kept not in header:
            differences.append(f"{c['old']} dropped as a duplicate of {kept}, which the table lacks")
            continue
        k = header.index(kept)
        differences += [f"row {r}: {c['old']} = {row[at]!r} but {kept} = {row[k]!r}"
                        for r, row in enumerate(rows) if row[at] != row[k]]
        header = header[:at] + header[at + 1:]
        rows = [row[:at] + row[at + 1:] for row in rows]
        cls = [(n, kk) for n, kk in cls if n != c["old"]]
        applied.append(f"{c['old']} dropped ({c['why']})")
    return header, rows, cls, applied, differences


def kind_of(meta_path: Path):
    """`experiment.kind` of the spec a NAME.meta.toml records (None if it records none)."""
    meta = tomllib.loads(meta_path.read_text())
    return meta.get("spec", {}).get("base", {}).get("experiment", {}).get("kind")


def classes(meta_path: Path) -> dict:
    """{table: [(column, class), ...]} from a NAME.meta.toml."""
    meta = tomllib.loads(meta_path.read_text())
    return {
        table: [(c["name"], c["class"]) for c in cols]
        for table, cols in meta.get("columns", {}).items()
    }


def read_csv(path: Path, drop=()):
    """(header, rows) without the columns named in `drop`."""
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    keep = [i for i, c in enumerate(rows[0]) if c not in drop]
    rows = [[r[i] for i in keep] for r in rows]
    return rows[0], rows[1:]


def table_files(exp_dir: Path, name: str):
    """(table name, path) of every CSV of one experiment: `main` and its side tables."""
    out = []
    for p in sorted(exp_dir.glob(f"{name}*.csv")):
        rest = p.name[len(name):]
        if rest == ".csv":
            out.append(("main", p))
        elif rest.startswith(".") and rest.count(".") == 2:
            out.append((rest[1:-4], p))
    return out


def compare_table(label, old_path, new_path, old_cls, new_cls, added=(), changes=()):
    """Returns (ok, line); the columns `added` are dropped from the new table first, and the old
    table is brought up to date by `changes` (header_changes)."""
    problems = []
    if not new_path.exists():
        return False, f"{label}: missing in the new folder"
    old_header, old_rows = read_csv(old_path)
    old_header, old_rows, old_cls, mapped, problems = upgrade(changes, old_header, old_rows, old_cls)
    new_header, new_rows = read_csv(new_path, added)
    new_cls = [(c, k) for c, k in new_cls if c not in added]
    if old_header != new_header:
        gone = [c for c in old_header if c not in new_header]
        added = [c for c in new_header if c not in old_header]
        return False, (
            f"{label}: headers differ (only old: {gone[:8]}, only new: {added[:8]}"
            + ("" if gone or added else ", same names in another order")
            + ")"
        )
    if old_cls != new_cls:
        diff = [(a, b) for a, b in zip(old_cls, new_cls) if a != b]
        problems.append(f"classes differ in the metadata: {diff[:5]}")
    declared = dict(old_cls)
    undeclared = [c for c in old_header if c not in declared]
    if undeclared:
        problems.append(f"columns without a class in the metadata: {undeclared[:5]}")
    compared = [i for i, c in enumerate(old_header) if declared.get(c, "measured") != "timing"]
    if len(old_rows) != len(new_rows):
        problems.append(f"{len(old_rows)} rows in the old table, {len(new_rows)} in the new")
    differ = 0
    shown = []
    for r, (a, b) in enumerate(zip(old_rows, new_rows)):
        for i in compared:
            if a[i] != b[i]:
                differ += 1
                if len(shown) < SHOWN:
                    shown.append(f"row {r} {old_header[i]}: {a[i]!r} → {b[i]!r}")
    if differ:
        problems.append(f"{differ} cell(s) differ: " + "; ".join(shown))
    line = (
        f"{label}: {len(compared)} measured columns of {len(old_header)} compared, "
        f"{len(old_rows)} rows, {differ} differ"
    ) + ("".join(f" | mapped: {m}" for m in mapped))
    if problems:
        return False, line + " — " + " | ".join(problems)
    return True, line


def compare_streams(label, old_path, new_path, old_cls, z_max, changes=()):
    """Returns (ok, line) for two runs on different random streams (see --stream-changed)."""
    if not new_path.exists():
        return False, f"{label}: missing in the new folder"
    old_header, old_rows = read_csv(old_path)
    old_header, old_rows, old_cls, _, _ = upgrade(changes, old_header, old_rows, old_cls)
    new_header, new_rows = read_csv(new_path)
    if old_header != new_header:
        return False, f"{label}: headers differ"
    if len(old_rows) != len(new_rows):
        # Rows that are bins or levels of the data (a histogram's range) may follow the stream.
        return True, f"{label}: {len(old_rows)} rows → {len(new_rows)}, not compared"
    declared = dict(old_cls)
    col = {c: i for i, c in enumerate(old_header)}
    params_differ, moved, worst, over = 0, 0, (0.0, ""), []
    for a, b in zip(old_rows, new_rows):
        for c, i in col.items():
            kind = declared.get(c, "measured")
            if kind == "timing" or a[i] == b[i]:
                continue
            if kind == "parameter":
                params_differ += 1
                continue
            moved += 1
            se = c[: -len("_mean")] + "_se" if c.endswith("_mean") else None
            if se not in col:
                continue
            try:
                ma, mb, sa, sb = (float(a[i]), float(b[i]), float(a[col[se]]), float(b[col[se]]))
            except ValueError:
                continue
            if not all(math.isfinite(v) for v in (ma, mb, sa, sb)) or sa == sb == 0.0:
                continue
            z = abs(ma - mb) / math.hypot(sa, sb)
            worst = max(worst, (z, c))
            if z > z_max:
                over.append(f"{c} z = {z:.2f}")
    line = (
        f"{label}: {moved} measured cells moved, largest |z| of a mean {worst[0]:.2f}"
        + (f" ({worst[1]})" if worst[1] else "")
    )
    problems = []
    if params_differ and not label.count("."):
        problems.append(f"{params_differ} parameter cell(s) differ")
    elif params_differ:
        # A side table's rows (levels, bins) follow the data: misaligned rows cannot be compared.
        return True, f"{label}: rows keyed by the data moved with the stream ({params_differ} key cells), not compared"
    if over:
        problems.append(f"{len(over)} mean(s) beyond {z_max} SE: " + "; ".join(over[:SHOWN]))
    return (not problems), line + (" — " + " | ".join(problems) if problems else "")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old", type=Path, help="folder of the reference results")
    ap.add_argument("new", type=Path, help="folder of the results to check")
    ap.add_argument("--added", action="append", default=[], metavar="COLUMN",
                    help="a column only the new tables have (dropped before comparing)")
    ap.add_argument("--stream-changed", type=float, metavar="Z",
                    help="the random streams differ: means must agree within Z standard errors")
    args = ap.parse_args()
    ok_all = True
    n_tables = 0
    experiments = sorted(p for p in args.old.iterdir() if (p / f"{p.name}.meta.toml").is_file())
    if not experiments:
        print(f"no experiment folders (NAME/NAME.meta.toml) in {args.old}", file=sys.stderr)
        return 1
    for exp in experiments:
        name = exp.name
        new_exp = args.new / name
        if not (new_exp / f"{name}.meta.toml").is_file():
            print(f"{name}: no {name}.meta.toml in {args.new}")
            ok_all = False
            continue
        old_meta, new_meta = classes(exp / f"{name}.meta.toml"), classes(new_exp / f"{name}.meta.toml")
        kind = kind_of(exp / f"{name}.meta.toml")
        old_tables = table_files(exp, name)
        new_tables = {t for t, _ in table_files(new_exp, name)}
        for extra in sorted(new_tables - {t for t, _ in old_tables}):
            print(f"{name}.{extra}: only in the new folder")
            ok_all = False
        for table, path in old_tables:
            n_tables += 1
            label = name if table == "main" else f"{name}.{table}"
            added = [a.split(":", 1)[-1] for a in args.added
                     if ":" not in a or a.split(":", 1)[0] == table]
            changes = header_changes(kind, table) if kind else []
            if args.stream_changed is not None:
                ok, line = compare_streams(
                    label, path, new_exp / path.name, old_meta.get(table, []), args.stream_changed, changes
                )
            else:
                ok, line = compare_table(
                    label,
                    path,
                    new_exp / path.name,
                    old_meta.get(table, []),
                    new_meta.get(table, []),
                    added,
                    changes,
                )
            ok_all &= ok
            print(("" if ok else "DIFFERS ") + line)
    agree = "all means within the SE bound" if args.stream_changed is not None else "all equal in their measured columns"
    print(f"{n_tables} tables of {len(experiments)} experiments: " + (agree if ok_all else "DIFFERENCES"))
    return 0 if ok_all else 1


if __name__ == "__main__":
    sys.exit(main())
