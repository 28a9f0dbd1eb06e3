"""What the claims engine reads: result tables (pooled over separate runs where there are several),
rows selected and grouped as a rule says, quantities in an accounting, and the checks of what a
rule needs that the tables may lack ("needs …").

Runs. A run is one `raycost run` of a spec. Several runs of one experiment live beside its pooled
table as results/NAME/runs/RUN/NAME.csv (with the same side tables, NAME.frames.csv …); the engine
pools their main tables point by point with the runs as clusters (raycost_stats.pool_runs) and
keys the clusters of a side table by (run, replica). Without a runs folder the committed table is
one run.
"""

import csv
import glob
import math
import os

import raycost_tables
from raycost_stats import pool_runs


class Missing(Exception):
    """Something a rule needs is not in the tables; its message completes "needs …"."""


def num(v):
    if v is None or v == "":
        return math.nan
    try:
        return float(v)
    except ValueError:
        return v


table_file = raycost_tables.table_file


def read_csv(path):
    """The rows of a committed table, its header checked against the columns its metadata
    declares (raycost_tables)."""
    try:
        return raycost_tables.read_rows(path, num)[1]
    except raycost_tables.TableError as e:
        raise SystemExit("error: %s" % e) from None


def close(a, b):
    """Equality for table cells: numbers to 1e-9 relative, text as text ("true" = True)."""
    if isinstance(b, bool):
        return a == b or (isinstance(a, str) and a.lower() == str(b).lower()) or (
            isinstance(a, float) and a == float(b))
    if isinstance(a, float) and isinstance(b, (int, float)):
        return abs(a - b) <= 1e-9 * max(1.0, abs(b))
    return a == b


def matches(row, select):
    """Whether a row has every column = value of `select` (a list of values: any of them)."""
    for k, v in (select or {}).items():
        cell = row.get(k)
        allowed = v if isinstance(v, list) else [v]
        if not any(close(cell, a) for a in allowed):
            return False
    return True


class Tables:
    """The tables under RESULTS, read once each."""

    def __init__(self, results):
        self.results = results
        self._cache = {}

    def path(self, name, side=None, run=None):
        file = "%s.%s.csv" % (name, side) if side else "%s.csv" % name
        if run is None:
            return os.path.join(self.results, name, file)
        return os.path.join(self.results, name, "runs", run, file)

    def exists(self, name, side=None):
        return os.path.exists(table_file(self.path(name, side)))

    def run_ids(self, name):
        """The separate runs of NAME: the folders results/NAME/runs/RUN holding NAME.csv."""
        found = glob.glob(os.path.join(self.results, name, "runs", "*", "%s.csv" % name))
        return sorted(os.path.basename(os.path.dirname(p)) for p in found)

    def runs(self, name, side=None):
        """[(run id, rows)] of every run ("" for the committed table alone)."""
        key = ("runs", name, side)
        if key not in self._cache:
            ids = self.run_ids(name)
            if ids:
                self._cache[key] = [(i, read_csv(self.path(name, side, i))) for i in ids]
            else:
                self._cache[key] = [("", self._read(name, side))]
        return self._cache[key]

    def _read(self, name, side):
        p = table_file(self.path(name, side))
        if not os.path.exists(p):
            raise Missing("table %s" % os.path.relpath(p, self.results))
        return read_csv(p)

    def rows(self, name, side=None):
        """The main table pooled over runs (run-level SEs) or, for a side table, the committed one."""
        key = ("rows", name, side)
        if key not in self._cache:
            runs = self.runs(name) if side is None else []
            if side is None and len(runs) > 1:
                first = runs[0][1]
                metrics = sorted({k[:-5] for k in first[0] if k.endswith("_mean") and k[:-5] + "_se" in first[0]})
                self._cache[key] = pool_runs([r for _, r in runs], ["point"], metrics)
            else:
                self._cache[key] = self._read(name, side)
        return self._cache[key]

    def n_runs(self, name):
        return len(self.run_ids(name)) or 1

    def joined(self, name, side):
        """Side-table rows with their main row's columns added (the side row's own cells win)."""
        main = {r["point"]: r for r in self.rows(name)}
        out = []
        for r in self.rows(name, side):
            j = dict(main.get(r["point"], {}))
            j.update(r)
            out.append(j)
        return out


# ----------------------------------------------------------------------------------------------
# grouping and labels


def short(key):
    return key.split(".")[-1]


def show(v):
    if isinstance(v, float):
        if v == int(v) and abs(v) < 1e15:
            return "%d" % v
        return "%g" % v
    if isinstance(v, str) and "/" in v:
        return v.split("/")[-1].rsplit(".", 1)[0]
    return str(v)


def label(row, keys, prefix=""):
    parts = ["%s %s" % (short(k), show(row.get(k))) for k in keys if k in row]
    text = ", ".join(parts)
    return (prefix + (": " + text if text else "")) if prefix else text


def group(rows, keys):
    """Rows grouped by the values of `keys`, in first-seen order: [(key values, rows)]."""
    out = {}
    for r in rows:
        out.setdefault(tuple(show(r.get(k)) for k in keys), []).append(r)
    return list(out.items())


# ----------------------------------------------------------------------------------------------
# quantities


def terms_of(ctx, family, accounting):
    """The {column: weight} an accounting charges for a cost family."""
    acc = ctx.accountings.get(accounting)
    if acc is None or family not in acc:
        raise ValueError("accounting %r has no cost %r (claims/preregistered.toml)" % (accounting, family))
    return acc[family]


def weight(row, w):
    """A term's weight: a number, or "/COL" (divide by the row's COL)."""
    if isinstance(w, str):
        if not w.startswith("/"):
            raise ValueError("a weight is a number or \"/COLUMN\", got %r" % w)
        d = row.get(w[1:])
        if not isinstance(d, float) or d != d or d == 0:
            raise Missing("column %s" % w[1:])
        return 1.0 / d
    return float(w)


def quantity(row, terms, source=""):
    """(mean, se, dof) of Σ weight·column in a table row. A column M with M_mean/M_se brings its SE
    (independent terms); a plain column M has none (se NaN). dof: the smallest of the terms'."""
    mean, var, dofs, exact = 0.0, 0.0, [], False
    for col, w in terms.items():
        k = weight(row, w)
        if col + "_mean" in row:
            m, s = row[col + "_mean"], row.get(col + "_se", math.nan)
            c = row.get(col + "_clusters")
            c = c if isinstance(c, float) and c == c else row.get(col + "_n", math.nan)
            dofs.append(c - 1 if isinstance(c, float) else math.nan)
        elif col in row:
            m, s = row[col], math.nan
            exact = True
        else:
            raise Missing("column %s%s" % (col, " in " + source if source else ""))
        if not isinstance(m, float):
            raise Missing("a number in column %s%s" % (col, " in " + source if source else ""))
        mean += k * m
        var += (k * s) ** 2 if s == s else 0.0
    se = math.nan if exact else math.sqrt(var)
    d = min((x for x in dofs if x == x), default=math.nan)
    return mean, se, d


def frame_value(frame_row, terms):
    total = 0.0
    for col, w in terms.items():
        v = frame_row.get(col)
        if not isinstance(v, float):
            raise Missing("column %s in the frames table" % col)
        total += float(w) * v
    return total


def per_replica(tables, name, points_by_slot, terms, first_frame=1, extra=None):
    """Clusters for raycost_stats.Clustered from the frames tables of every run of NAME:
    {(run, replica): [value per slot]}, a slot's value being the mean over frames ≥ first_frame of
    Σ weight·column for that slot's point. `extra` = [(point, terms, frame)]: more slots read at
    one frame (e.g. the index build at frame 0). Every slot must have every replica."""
    out = {}
    for run, frames in tables.runs(name, "frames"):
        by = {}
        for f in frames:
            by.setdefault((f["point"], f["replica"]), []).append(f)
        reps = sorted({rep for (_, rep) in by})
        for rep in reps:
            vals = []
            for p in points_by_slot:
                fr = [f for f in by.get((p, rep), []) if f["frame"] >= first_frame]
                if not fr:
                    raise Missing("frames ≥ %d of point %s, replica %s in %s" % (first_frame, show(p), show(rep), name))
                vals.append(sum(frame_value(f, terms) for f in fr) / len(fr))
            for p, t, frame in extra or []:
                fr = [f for f in by.get((p, rep), []) if f["frame"] == frame]
                if not fr:
                    raise Missing("frame %d of point %s in %s" % (frame, show(p), name))
                vals.append(frame_value(fr[0], t))
            out[(run, rep)] = vals
    return out


# ----------------------------------------------------------------------------------------------
# what a rule needs


def requirement_needs(req, tables, sources, select):
    """The "needs …" texts of a claim's [claim.requires] against its source tables."""
    needs = []
    rows = []
    for s in sources:
        try:
            rows += [r for r in tables.rows(s) if matches(r, select)]
        except Missing as e:
            needs.append(str(e))
    for col, want in (req.get("values") or {}).items():
        # A required value of a column the rule also selects on (detp-unbiased selects the paper's
        # edge and requires the clamp beside it) is looked for with that column's own selection
        # left out: the requirement is about what the tables hold.
        mine = rows if col not in (select or {}) else values_rows(tables, sources, select, col)
        have = {show(r.get(col)) for r in mine}
        lack = [show(v) for v in want if show(v) not in have]
        if lack:
            needs.append("%s = %s" % (col, ", ".join(lack)))
    if req.get("common_random_numbers"):
        col = "experiment.common_random_numbers"
        if not rows or not all(close(r.get(col), True) for r in rows):
            needs.append("common random numbers between sweep points (spec key %s = true)" % col)
    g = req.get("grid")
    if g:
        needs += grid_needs(g, rows)
    for side, cols in (req.get("columns") or {}).items():
        for s in sources:
            needs += column_needs(tables, s, side, cols)
    return needs


def values_rows(tables, sources, select, col):
    """The sources' rows matching `select` without its condition on `col`."""
    rest = {k: v for k, v in select.items() if k != col}
    out = []
    for s in sources:
        try:
            out += [r for r in tables.rows(s) if matches(r, rest)]
        except Missing:
            pass
    return out


def optional_missing(req, tables, sources, select):
    """The values of [claim.requires].optional the tables do not have (shown, not needed)."""
    rows = []
    for s in sources:
        try:
            rows += [r for r in tables.rows(s) if matches(r, select)]
        except Missing:
            pass
    out = []
    for col, want in (req.get("optional") or {}).items():
        have = {show(r.get(col)) for r in rows}
        out += ["%s = %s" % (col, show(v)) for v in want if show(v) not in have]
    return out


def grid_needs(g, rows):
    """A swept column must cover [from, to] in steps no larger than `step`, including `include`."""
    col, lo, hi, step = g["column"], g["from"], g["to"], g["step"]
    xs = sorted({r[col] for r in rows if isinstance(r.get(col), float)})
    inside = [x for x in xs if lo - 1e-9 <= x <= hi + 1e-9]
    gaps = [b - a for a, b in zip(inside, inside[1:])]
    bad = (not inside or inside[0] > lo + 1e-9 or inside[-1] < hi - 1e-9
           or any(d > step + 1e-9 for d in gaps))
    out = []
    if bad:
        out.append("%s over %g–%g in steps ≤ %g (the table has %s)" % (
            col, lo, hi, step, ", ".join("%g" % x for x in xs) or "none"))
    missing = [v for v in g.get("include", []) if not any(abs(v - x) < 1e-6 for x in xs)]
    if missing:
        out.append("%s = %s in the grid" % (col, ", ".join("%.4g" % v for v in missing)))
    return out


def column_needs(tables, name, side, cols):
    """Columns a rule reads from a table (side "main" = NAME.csv)."""
    s = None if side == "main" else side
    try:
        rows = tables.rows(name, s)
    except Missing as e:
        return [str(e)]
    have = set(rows[0]) if rows else set()
    return ["column %s in %s" % (c, os.path.basename(tables.path(name, s)))
            for c in cols if c not in have and c + "_mean" not in have]


def runs_needs(tables, sources, need):
    """A timed accounting needs `need` separate runs of every source."""
    out = []
    for s in sources:
        k = tables.n_runs(s)
        if k < need:
            out.append("≥ %d separate runs of %s (has %d; results/%s/runs/RUN/)" % (need, s, k, s))
    return out
