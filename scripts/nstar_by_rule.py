#!/usr/bin/env python3
"""N* per DETP configuration and target, side by side for several `raycost crossover` folders:
what the disc radius rules change on one scene ("before": a crossover of the fixed-d fronts;
"after": one of the rules' fronts).

Run from the repository root:
    python3 scripts/nstar_by_rule.py results/crossover-rules-cornell [results/issue27-crossover-cornell …]

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


def best_lines(folder):
    """Per target and radius rule family, the DETP configuration (either engine) with the smallest
    finite N*, or 'never' where none reaches the target."""
    rows = [r for r in read(folder) if rule(r)]
    out = ["## %s (scene %s): smallest DETP N* per radius rule" % (
        folder, rows[0]["scene"] if rows else "?")]
    families = ["d fixed", "kappa", "schedule", "kappa + schedule"]
    for target in sorted({r["target"] for r in rows}, reverse=True):
        for fam in families:
            mine = [r for r in rows if r["target"] == target and family(r) == fam]
            if not mine:
                continue
            finite = [r for r in mine if isinstance(r["n_star"], float) and math.isfinite(r["n_star"])]
            if finite:
                r = min(finite, key=lambda r: r["n_star"])
                what = "%s direct=%s edge=%s: %s" % (r["method"], r["direct"], r["edge"], cell(r))
            else:
                # The reason of the configuration closest to the target: the smallest N_eps if
                # any reaches it (then the cost is what is missing), else the lowest floor.
                def closeness(r):
                    n, f = r["photons"], r["error_floor"]
                    n = n if isinstance(n, float) and math.isfinite(n) else math.inf
                    f = f if isinstance(f, float) and math.isfinite(f) else math.inf
                    return (n, f, r["reason"])
                near = min(mine, key=closeness)
                what = "never (%s)" % near["reason"].split("; model:")[0]
                if isinstance(near["photons"], float) and math.isfinite(near["photons"]):
                    what += "; its N_eps %.3g, %.3g× the largest measured" % (
                        near["photons"], near["photons"] / near.get("photons_measured_max", math.nan))
            out.append("%g %-16s %s" % (target, fam, what))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folders", nargs="+", help="raycost crossover output folders")
    ap.add_argument("--best", action="store_true",
                    help="per target and radius rule only the DETP configuration with the smallest N*")
    args = ap.parse_args(argv)
    for folder in args.folders:
        try:
            print("\n".join(best_lines(folder) if args.best else lines(folder)))
        except T.TableError as e:
            print("nstar_by_rule: %s" % e, file=sys.stderr)
            return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
