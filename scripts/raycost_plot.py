"""Shared helpers for the raycost plot scripts (scripts/plot_*.py).

Not a script itself: each plot_NAME.py imports it to read a results CSV, check its columns, group rows
by swept keys and draw "measured mean ± 95 % CI" against theory the same way in every figure.

CSV conventions (see the project's CONTRACT): a measured metric M has the columns M_mean, M_se, M_n and
M_clusters (the independent clusters behind M_se: a 95 % CI is Student-t on M_clusters − 1);
its theory M_theory, its bounds M_lower / M_upper; swept spec keys appear as columns named by their
dotted key (grid.cell_width, scene.intensity, ...).
"""

import argparse
import csv
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")  # non-interactive: the scripts only write PNG files

import matplotlib.pyplot as plt  # noqa: E402

import raycost_tables  # noqa: E402
from raycost_stats import ci95  # noqa: E402,F401  (re-exported: rp.ci95(row, metric))

#: multiplier of the standard error for a two-sided 95 % normal confidence interval (many clusters;
#: with few, ci95(row, metric) gives Student-t on the row's M_clusters − 1)
Z95 = 1.96
#: multiplier for 99 % (the tolerance the tests use for "measured agrees with theory")
Z99 = 2.58

#: one colour per role, so every figure reads the same way
COLORS = {
    "measured": "C0",
    "measured_mb": "C3",
    "theory": "black",
    "theory_mb": "C3",
    "plain": "0.45",
    "band": "C0",
    "model": "C2",
}


class PlotError(Exception):
    """A problem with the input (missing file or column); reported as `error: ...`, exit code 2."""


# --------------------------------------------------------------------------------------------------
# command line


def parse_args(doc, name, extra=None, argv=None, what=None):
    """argparse with description=doc, --input (default results/NAME/NAME.csv) and --output
    (default beside the CSV: NAME.png, or NAME.WHAT.png when `what` is given).

    `extra(parser)` may add more options. Returns the namespace with `output` filled in."""
    parser = argparse.ArgumentParser(
        description=doc, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    default_input = os.path.join("results", name, name + ".csv")
    parser.add_argument(
        "--input",
        "-i",
        default=default_input,
        metavar="CSV",
        help="results CSV written by `raycost run` (default: %(default)s)",
    )
    parser.add_argument(
        "--output",
        "-o",
        default=None,
        metavar="PNG",
        help="PNG to write (default: beside the CSV, %s)"
        % os.path.basename(default_png(default_input, what)),
    )
    parser.add_argument("--dpi", type=int, default=130, help="resolution of the PNG (default: %(default)s)")
    if extra is not None:
        extra(parser)
    args = parser.parse_args(argv)
    if args.output is None:
        args.output = default_png(args.input, what)
    return args


def default_png(csv_path, what=None):
    """results/NAME/NAME.csv -> results/NAME/NAME.png (or NAME.WHAT.png)."""
    base = csv_path[:-4] if csv_path.endswith(".csv") else csv_path
    # NAME.hist.csv -> NAME.hist.png, which is what we want for tables too
    return base + ("." + what if what else "") + ".png"


def sibling_csv(csv_path, table):
    """results/NAME/NAME.csv -> results/NAME/NAME.TABLE.csv."""
    base = csv_path[:-4] if csv_path.endswith(".csv") else csv_path
    return base + "." + table + ".csv"


def run(main):
    """Call main(), turning a PlotError into `error: ...` on stderr and exit code 2."""
    try:
        main()
    except PlotError as e:
        print("error: %s" % e, file=sys.stderr)
        sys.exit(2)


# --------------------------------------------------------------------------------------------------
# reading


def _convert(value):
    """'3' -> 3, '0.5' / 'NaN' / 'inf' -> float, '' -> None, anything else stays a string."""
    if value == "":
        return None
    try:
        return int(value)
    except ValueError:
        pass
    try:
        return float(value)  # also parses NaN, inf, -inf
    except ValueError:
        return value


def read_csv(path, required=()):
    """Read a results CSV into a list of dicts with numbers converted. Fails (PlotError) when the
    file is missing or empty, when its header is not the columns its metadata declares, or when a
    column of `required` is absent or undeclared (raycost_tables)."""
    if not os.path.exists(raycost_tables.table_file(path)):
        raise PlotError(
            "%s: no such file (run the experiment first (`raycost run SPEC.toml` or `raycost bench`), "
            "or pass --input)" % path
        )
    try:
        _, rows = raycost_tables.read_rows(path, _convert, required)
    except raycost_tables.TableError as e:
        raise PlotError(str(e)) from None
    if not rows:
        raise PlotError("%s: no data rows" % path)
    return rows


def require_columns(path, header, required):
    try:
        raycost_tables.check_header(path, header, required)
    except raycost_tables.TableError as e:
        raise PlotError(str(e)) from None


def spec_value(csv_path, key, row=None, default=None):
    """The value of spec key `key` (dotted) for a point: its column (every parameter has one in
    tables of this version; NaN there means the key was left out), else the spec's base value
    recorded in NAME.meta.toml beside the CSV ([spec.base.SECTION] KEY) for older tables, else
    `default`."""
    value = None if row is None else row.get(key)
    if value is not None and not (isinstance(value, float) and math.isnan(value)):
        return value
    meta = (csv_path[:-4] if csv_path.endswith(".csv") else csv_path) + ".meta.toml"
    try:
        import tomllib  # Python >= 3.11
    except ImportError:  # pragma: no cover - older Pythons: no meta lookup
        return default
    try:
        with open(meta, "rb") as f:
            node = tomllib.load(f)["spec"]["base"]
        for part in key.split("."):
            node = node[part]
        return node
    except (OSError, KeyError, TypeError, tomllib.TOMLDecodeError):
        return default


def measured_columns(*metrics):
    """['M_mean', 'M_se', ...] for each metric M."""
    cols = []
    for m in metrics:
        cols += [m + "_mean", m + "_se"]
    return cols


def has(rows, col):
    return bool(rows) and col in rows[0]


def col(rows, name):
    """Column as a list of floats (None and strings -> NaN)."""
    return [_num(r.get(name)) for r in rows]


def _num(v):
    if isinstance(v, bool):
        return float(v)
    if isinstance(v, (int, float)):
        return float(v)
    return math.nan


def group_by(rows, *keys):
    """Ordered {key tuple: rows} over the values of `keys` present (only keys that are columns
    count; with none, one group keyed ()). Groups keep first-appearance order, rows keep file order."""
    keys = [k for k in keys if has(rows, k)]
    groups = {}
    for r in rows:
        groups.setdefault(tuple(r[k] for k in keys), []).append(r)
    return keys, groups


def sort_by(rows, key):
    return sorted(rows, key=lambda r: _num(r.get(key)))


def group_label(keys, value):
    """('scene.intensity', 'grid.eye'), (0.5, 'corner') -> 'scene.intensity = 0.5, grid.eye = corner'."""
    return ", ".join("%s = %s" % (k, _fmt(v)) for k, v in zip(keys, value))


def _fmt(v):
    if isinstance(v, float):
        return "%g" % v
    return str(v)


# --------------------------------------------------------------------------------------------------
# drawing


def measured(ax, rows, x, metric, label=None, color=None, marker="o", z=None, **kw):
    """Measured mean with error bars against column x: the 95 % CI, Student-t on each row's
    M_clusters − 1 (ci95), or ± z·se where z is given."""
    xs = col(rows, x)
    ys = col(rows, metric + "_mean")
    if not has(rows, metric + "_se"):
        err = [0.0] * len(rows)
    elif z is None:
        err = [ci95(r, metric) for r in rows]
    else:
        err = [z * s for s in col(rows, metric + "_se")]
    err = [e if e == e else 0.0 for e in err]
    return ax.errorbar(
        xs,
        ys,
        yerr=err,
        fmt=marker,
        color=color or COLORS["measured"],
        ms=4.5,
        capsize=3,
        elinewidth=1.2,
        label=label if label is not None else "%s measured (mean ± 95 %% CI)" % metric,
        zorder=3,
        **kw,
    )


def theory(ax, rows, x, column, label=None, color=None, ls="-", **kw):
    """A theory column drawn as a line against column x."""
    return ax.plot(
        col(rows, x),
        col(rows, column),
        ls=ls,
        color=color or COLORS["theory"],
        lw=1.4,
        label=label if label is not None else column,
        zorder=2,
        **kw,
    )


def band(ax, rows, x, lower, upper, label=None, color=None, alpha=0.15, **kw):
    """Shaded band between two columns (bounds) against column x."""
    xs, lo, hi = col(rows, x), col(rows, lower), col(rows, upper)
    c = color or COLORS["band"]
    ax.fill_between(xs, lo, hi, color=c, alpha=alpha, lw=0, label=label, zorder=1, **kw)
    ax.plot(xs, lo, color=c, lw=0.6, alpha=0.6, zorder=1)
    ax.plot(xs, hi, color=c, lw=0.6, alpha=0.6, zorder=1)


def deviation(ax, rows, x, metric, theory_col=None, label=None, color=None, marker="o"):
    """(measured − theory)/se against x, with the ±1.96 and ±2.58 lines."""
    theory_col = theory_col or metric + "_theory"
    xs = col(rows, x)
    d = [
        (m - t) / s if s and s == s and s > 0 else math.nan
        for m, t, s in zip(col(rows, metric + "_mean"), col(rows, theory_col), col(rows, metric + "_se"))
    ]
    ax.plot(xs, d, marker, color=color or COLORS["measured"], ms=4.5, label=label, zorder=3)
    ax.axhline(0, color="black", lw=0.8)
    for lim, ls in ((Z95, ":"), (Z99, "--")):
        ax.axhline(lim, color="0.5", lw=0.8, ls=ls)
        ax.axhline(-lim, color="0.5", lw=0.8, ls=ls)
    finite = [abs(v) for v in d if v == v and abs(v) != math.inf]
    top = max([3.2] + [v * 1.15 for v in finite])
    ax.set_ylim(-top, top)
    ax.set_ylabel("(meas − theory) / se")
    return d


def rel_err(rows, metric, theory_col=None):
    """Max |measured − theory| / theory over rows (NaN-safe)."""
    theory_col = theory_col or metric + "_theory"
    errs = [
        abs(m - t) / abs(t)
        for m, t in zip(col(rows, metric + "_mean"), col(rows, theory_col))
        if m == m and t == t and t != 0 and abs(t) != math.inf
    ]
    return max(errs) if errs else math.nan


def text_box(ax, text, loc="upper left", fontsize=8):
    """A small boxed note inside an axes."""
    pos = {
        "upper left": (0.02, 0.98, "left", "top"),
        "upper right": (0.98, 0.98, "right", "top"),
        "lower left": (0.02, 0.02, "left", "bottom"),
        "lower right": (0.98, 0.02, "right", "bottom"),
    }[loc]
    ax.text(
        pos[0],
        pos[1],
        text,
        transform=ax.transAxes,
        ha=pos[2],
        va=pos[3],
        fontsize=fontsize,
        bbox=dict(boxstyle="round,pad=0.3", fc="white", ec="0.7", alpha=0.9),
        zorder=5,
    )


def log_scale(ax, x=False, y=False):
    """Log axes with plain labels ("0.1", "20", "1e+06"); minor ticks 2 and 5 are labelled too when
    the axis spans less than about two decades, so short ranges still read."""
    from matplotlib.ticker import FuncFormatter

    def major(v, _pos):
        return "%g" % v

    def minor_for(axis):
        def minor(v, _pos):
            lo, hi = axis.get_view_interval()
            if not (lo > 0 and hi > 0) or hi / lo > 150:
                return ""
            lead = round(v / 10 ** math.floor(math.log10(v) + 1e-9), 6)
            return "%g" % v if lead in (2.0, 5.0) else ""

        return minor

    for on, axis, setter in ((x, ax.xaxis, ax.set_xscale), (y, ax.yaxis, ax.set_yscale)):
        if on:
            setter("log")
            axis.set_major_formatter(FuncFormatter(major))
            axis.set_minor_formatter(FuncFormatter(minor_for(axis)))


def pad_log_limits(ax, values, factor=1.3, axis="x"):
    """Set a log axis' limits to the finite positive data range widened by `factor` each side."""
    vals = [v for v in values if v == v and 0 < v < math.inf]
    if not vals:
        return
    lim = (min(vals) / factor, max(vals) * factor)
    (ax.set_xlim if axis == "x" else ax.set_ylim)(*lim)


def positive(values):
    """True when every finite value is > 0 (so a log axis is safe)."""
    vals = [v for v in values if v == v]
    return bool(vals) and all(v > 0 for v in vals)


def subplots(nrows, ncols, panel_w=5.0, panel_h=3.8, **kw):
    """plt.subplots with a size proportional to the panel count, always returning a 2-D array."""
    fig, axes = plt.subplots(
        nrows, ncols, figsize=(panel_w * ncols, panel_h * nrows), squeeze=False, **kw
    )
    return fig, axes


def finish(fig, args):
    """Lay out the figure and write it where the command line says."""
    fig.tight_layout()
    save(fig, args.output, args.dpi)


def script(plot, doc, name, extra=None):
    """Entry point of a plot script: parse this process's arguments and draw, with `run`'s errors."""
    run(lambda: plot(parse_args(doc, name, extra=extra, argv=sys.argv[1:])))


def save(fig, path, dpi=130):
    """Write the PNG (creating its directory) and close the figure."""
    d = os.path.dirname(path)
    if d:
        os.makedirs(d, exist_ok=True)
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    print("wrote %s" % path)


# --------------------------------------------------------------------------------------------------
# DETP side tables


def with_params(csv_path, table, required=()):
    """Rows of the side table NAME.TABLE.csv, each extended with its point's parameter columns (the
    swept or set keys, which only the main table carries). Returns (main rows, joined rows)."""
    main = read_csv(csv_path)
    side = read_csv(sibling_csv(csv_path, table), required)
    params = [c for c in main[0].keys() if "." in c]
    by_point = {r["point"]: {k: r[k] for k in params} for r in main}
    for r in side:
        r.update(by_point.get(r["point"], {}))
    return main, side
