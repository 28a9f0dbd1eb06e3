#!/usr/bin/env python3
"""N* per DETP configuration and target, side by side for several `raycost crossover` folders:
what the disc radius rules change on one scene ("before": a crossover of the fixed-d fronts;
"after": one of the rules' fronts).

Run from the repository root:
    python3 scripts/nstar_by_rule.py results/crossover-rules-cornell [results/crossover-cornell …]

For every folder it prints one line per method configuration (method, detp.direct, detp.edge, the
radius rule: d fixed, κ = edge_radius_factor, or the schedule d·(N/N_ref)^(−β)) and per target:
N* with its bootstrap interval, the share of bootstrap draws that never reach the target, how far
the photons N_eps it rests on lie past the largest count the fronts measured (where they do), and
where N* is not finite the crossover's reason. It reads crossover.csv through the columns its metadata
declares (scripts/raycost_tables.py) and computes nothing: every number is the crossover's.
Standard library only.
"""

import argparse
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import raycost_tables as T  # noqa: E402

COLUMNS = (
    "scene",
    "target",
    "method",
    "direct",
    "edge",
    "photons",
    "error_floor",
    "disc_radius",
    "edge_radius_factor",
    "radius_schedule_exponent",
    "n_star",
    "n_star_lo",
    "n_star_hi",
    "never_fraction",
    "reason",
)


def number(text):
    """A cell as a float where it is one, else the text."""
    try:
        return float(text)
    except ValueError:
        return text


def rule(row):
    """The radius rule of a DETP row, in words ('' for the photon maps and path tracing)."""
    if not isinstance(row["disc_radius"], float) or math.isnan(row["disc_radius"]):
        return ""
    kappa, beta = row["edge_radius_factor"], row["radius_schedule_exponent"]
    parts = []
    if isinstance(kappa, float) and not math.isnan(kappa):
        parts.append("kappa=%g" % kappa)
    if isinstance(beta, float) and not math.isnan(beta) and beta > 0:
        parts.append("schedule beta=%.3g" % beta)
    return " ".join(parts) or "d fixed"


def label(row):
    """Method, direct, edge and radius rule of a row."""
    parts = [row["method"], "direct=%s" % row["direct"]]
    if isinstance(row["edge"], str) and row["edge"] not in ("", "NaN"):
        parts.append("edge=%s" % row["edge"])
    r = rule(row)
    if r:
        parts.append("d=%g %s" % (row["disc_radius"], r))
    return " ".join(parts)


def past_data(row):
    """' (N_eps k× past the data)' where the photons N_eps exceed the largest count the fronts
    measured (column photons_measured_max, absent in crossovers written before it), else ''."""
    n, top = row["photons"], row.get("photons_measured_max", float("nan"))
    if isinstance(n, float) and isinstance(top, float) and n > top:
        return " (N_eps %.3g, %.3g× past the data)" % (n, n / top)
    return ""


def cell(row):
    """N* [lo, hi] (never share), or the reason where N* is not finite."""
    n = row["n_star"]
    if isinstance(n, float) and math.isfinite(n):
        return "%.3g [%.3g, %.3g] never %.2f%s" % (
            n,
            row["n_star_lo"],
            row["n_star_hi"],
            row["never_fraction"],
            past_data(row),
        )
    return "never: %s" % row["reason"]


def read(folder):
    """The rows of FOLDER/crossover.csv as dicts."""
    _, rows = T.read_rows(os.path.join(folder, "crossover.csv"), number, COLUMNS)
    return rows


def lines(folder):
    """The printed lines of one crossover folder."""
    rows = read(folder)
    out = ["## %s (scene %s)" % (folder, rows[0]["scene"] if rows else "?")]
    for target in sorted({r["target"] for r in rows}, reverse=True):
        out.append("target %g:" % target)
        for r in sorted((r for r in rows if r["target"] == target), key=label):
            out.append("  %-72s %s" % (label(r), cell(r)))
    return out


def family(row):
    """The radius rule's family: d fixed, kappa, schedule or kappa + schedule."""
    r = rule(row)
    return {"d fixed": "d fixed", "kappa=0.5": "kappa"}.get(r, r.split(" beta")[0].replace(
        "kappa=0.5 schedule", "kappa + schedule"))


FAMILIES = ["d fixed", "kappa", "schedule", "kappa + schedule"]


def finite_n_star(row):
    """Whether a row's N* is a finite number."""
    return isinstance(row["n_star"], float) and math.isfinite(row["n_star"])


def best_of(rows, target, fam):
    """The DETP row of radius rule family `fam` at `target` with the smallest finite N*, else the
    one closest to the target (the smallest N_eps if any reaches it, so the cost is what is missing;
    else the lowest floor), whose reason says why none does; None where the family has no row."""
    mine = [r for r in rows if r["target"] == target and family(r) == fam]
    if not mine:
        return None
    finite = [r for r in mine if finite_n_star(r)]
    if finite:
        return min(finite, key=lambda r: r["n_star"])

    def closeness(r):
        n, f = r["photons"], r["error_floor"]
        n = n if isinstance(n, float) and math.isfinite(n) else math.inf
        f = f if isinstance(f, float) and math.isfinite(f) else math.inf
        return (n, f, r["reason"])
    return min(mine, key=closeness)


def never_text(row):
    """Why a row's N* is not finite: its reason without the cost model's echo, and how far the
    photons N_eps it would need lie past the largest count measured."""
    what = "never (%s)" % row["reason"].split("; model:")[0]
    if isinstance(row["photons"], float) and math.isfinite(row["photons"]):
        what += "; its N_eps %.3g, %.3g× the largest measured" % (
            row["photons"], row["photons"] / row.get("photons_measured_max", math.nan))
    return what


def best_lines(folder):
    """Per target and radius rule family, the DETP configuration (either engine) with the smallest
    finite N*, or 'never' where none reaches the target."""
    rows = [r for r in read(folder) if rule(r)]
    out = ["## %s (scene %s): smallest DETP N* per radius rule" % (
        folder, rows[0]["scene"] if rows else "?")]
    for target in sorted({r["target"] for r in rows}, reverse=True):
        for fam in FAMILIES:
            r = best_of(rows, target, fam)
            if r is None:
                continue
            if finite_n_star(r):
                what = "%s direct=%s edge=%s: %s" % (r["method"], r["direct"], r["edge"], cell(r))
            else:
                what = never_text(r)
            out.append("%g %-16s %s" % (target, fam, what))
    return out


def sci(x):
    """A number as README writes it: 1.6·10³ (two significant digits), ∞ for infinity."""
    if not math.isfinite(x):
        return "∞" if x > 0 else "NaN"
    if x == 0:
        return "0"
    e = math.floor(math.log10(abs(x)))
    m = round(x / 10 ** e, 1)
    if abs(m) >= 10:
        m, e = m / 10, e + 1
    sup = str(e).translate(str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹"))
    return "%g·10%s" % (m, sup)


def times(x):
    """A ratio in two significant digits, without an exponent: 1.1×, 44×, 1 100×."""
    if not math.isfinite(x) or x < 10:
        return "%.2g×" % x
    r = int(round(x, 1 - int(math.floor(math.log10(x)))))
    return "{:,}×".format(r).replace(",", " ")


SHORT = {"sphere-cache": "sphere cache", "disc-index": "disc index", "nee": "NEE",
         "photons": "photons", "clamp-first-hit": "clamp", "paper": "paper's edge"}


def why_never(row):
    """A short 'never' cell: the floor, a flattening error curve, no timing, or the reason as is;
    and the photons N_eps where the fit gives them."""
    reason = row["reason"].split("; model:")[0]
    if "error floor √B = " in reason:
        floor = float(reason.split("error floor √B = ")[1].split()[0])
        why = "floor %.3g %%" % (100 * floor)
    elif "flattens" in reason:
        why = "the error curve flattens"
    elif "no cost sweep" in reason:
        why = "not timed over n_P"
    else:
        why = reason
    n, top = row["photons"], row.get("photons_measured_max", math.nan)
    if isinstance(n, float) and math.isfinite(n):
        why += "; N_ε %s (%s the data)" % (sci(n), times(n / top))
    return "never: " + why


def markdown_cell(row):
    """N* [lo, hi] with the configuration reaching it, or why never."""
    if row is None:
        return "–"
    if not finite_n_star(row):
        return why_never(row)
    text = "**%s** [%s, %s]: %s, %s, %s" % (
        sci(row["n_star"]), sci(row["n_star_lo"]), sci(row["n_star_hi"]),
        SHORT.get(row["method"], row["method"]), SHORT.get(row["direct"], row["direct"]),
        SHORT.get(row["edge"], row["edge"]))
    n, top = row["photons"], row.get("photons_measured_max", math.nan)
    if isinstance(n, float) and n > top:
        text += " (N_ε %s the data)" % times(n / top)
    return text


def markdown_lines(folders):
    """One markdown table over all folders: per scene and target, each radius rule family's
    smallest DETP N* (either engine, any direct light and edge remedy) or why none is finite."""
    out = ["| scene | ε | d fixed | κ = 0.5 | schedule d(N) | κ = 0.5 + schedule |",
           "|---|---|---|---|---|---|"]
    for folder in folders:
        rows = [r for r in read(folder) if rule(r)]
        scene = rows[0]["scene"] if rows else "?"
        for target in sorted({r["target"] for r in rows}, reverse=True):
            cells = [markdown_cell(best_of(rows, target, fam)) for fam in FAMILIES]
            out.append("| %s | %g %% | %s |" % (scene, 100 * target, " | ".join(cells)))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folders", nargs="+", help="raycost crossover output folders")
    ap.add_argument("--best", action="store_true",
                    help="per target and radius rule only the DETP configuration with the smallest N*")
    ap.add_argument("--markdown", action="store_true",
                    help="as --best, one markdown table over all folders (README's)")
    args = ap.parse_args(argv)
    if args.markdown:
        try:
            print("\n".join(markdown_lines(args.folders)))
        except T.TableError as e:
            print("nstar_by_rule: %s" % e, file=sys.stderr)
            return 2
        return 0
    for folder in args.folders:
        try:
            print("\n".join(best_lines(folder) if args.best else lines(folder)))
        except T.TableError as e:
            print("nstar_by_rule: %s" % e, file=sys.stderr)
            return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
