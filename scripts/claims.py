#!/usr/bin/env python3
"""The claims of both papers, judged from the result tables by the rules registered in
claims/preregistered.toml (format and procedure: claims/README.md).

For every claim: check what its rule needs (tables, scenes, index kinds, grids, columns, separate
runs for seconds), compute its statistic on every unit listed (claims_measures, claims_levels,
claims_engines), judge each unit and the claim by the registered rule (claims_rules), compute what
goes beside (other accountings, variants, derived figures) and write

  results/claims.toml      the engine's version, then one [[claim]] per claim: headline, measured, units, verdict
                           (text), outcome (one of holds, holds-in-part, differs, refuted,
                           inconclusive), rule, accounting
  README.md                the claims table between <!-- claims:begin --> and <!-- claims:end -->:
                           one line a claim (its headline: the number held against the paper's)
  docs/claims.md           one section a claim: the verdict's reason, the rule, what is beside,
                           every judged unit (the `units` of results/claims.toml)
  claims/engine-versions.toml  the engine's versions and every claim's outcome under each
                           (claims_version.py): a version whose outcome differs from the one before
                           it under the same rule, or new tables that change an outcome, need that
                           claim's history entry, else nothing is written and --check fails

This file holds no verdict, window or claim-specific number: they are all in the pre-registration
(scripts/tests/test_claims.py checks it).

Usage:
  python3 scripts/claims.py            # rewrite results/claims.toml, README's table, docs/claims.md
  python3 scripts/claims.py --check    # exit 1 if any differs from what the tables give, if the
                                       # engine changed without a recorded version, or if a
                                       # verdict changed without a history entry (CI)
  python3 scripts/claims.py --results DIR --prereg FILE --print   # judge other tables, print only
"""

import argparse
import math
import os
import sys
import tomllib

import claims_engines
import claims_levels
import claims_measures
import claims_rules as R
import claims_version as V
from claims_data import Missing, Tables, optional_missing, requirement_needs, runs_needs
from claims_derived import DERIVED

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
BEGIN, END = "<!-- claims:begin -->", "<!-- claims:end -->"
DOC = "docs/claims.md"  # every claim's section with every unit (README's rows link to it)
BUSY_CORES = 0.25  # raycost's own busy-machine threshold (src/output/meta.rs)
UNITS_LISTED = 8   # longer unit lists are summarised: counts, then the units that are not inside
SHORT_HASH = 7     # a commit is shown by its first 7 hex digits, as git does

KINDS = {
    "band": claims_measures.kind_band,
    "z-gof": claims_measures.kind_z_gof,
    "p-values": claims_measures.kind_p_values,
    "slope": claims_measures.kind_slope,
    "value": claims_measures.kind_value,
    "share": claims_measures.kind_share,
    "zero-count": claims_measures.kind_zero_count,
    "level-law": claims_levels.kind_level_law,
    "peak-level": claims_levels.kind_peak_level,
    "level-ratio": claims_levels.kind_level_ratio,
    "crossover": claims_engines.kind_crossover,
    "optimum": claims_engines.kind_optimum,
    "engine-ratio": claims_engines.kind_engine_ratio,
    "break-even": claims_engines.kind_break_even,
    "bias": claims_engines.kind_bias,
    "predictor": claims_engines.kind_predictor,
}

REQUIRES = {"values", "optional", "common_random_numbers", "grid", "columns"}  # [claim.requires] keys
REQUIRED = ("id", "claim", "reference", "paper", "rule", "registered", "statistic", "accounting", "verdict", "note")


class Context:
    """What every kind reads: the tables, the registered defaults and accountings."""

    def __init__(self, tables, prereg):
        self.tables = tables
        self.defaults = prereg["defaults"]
        self.accountings = prereg.get("accounting", {})
        self.level = self.defaults["level"]
        self.draws = self.defaults["draws"]
        self.seed = self.defaults["seed"]
        self.min_spheres = self.defaults["min_spheres"]
        self.commits = prereg.get("commits", {})


def load(path):
    """The pre-registration, checked: every claim has the keys a rule needs and a known statistic."""
    with open(path, "rb") as f:
        pre = tomllib.load(f)
    check(pre, path)
    return pre


def check(pre, path):
    """Refuses a pre-registration a rule could not be read from: missing keys, an unknown statistic,
    a verdict that is not an outcome, a rule id not of the form CLAIM-ID/N, a history entry without
    the verdict it gave or with the current rule's id (a changed rule needs a new id)."""
    ids = set()
    for c in pre["claim"]:
        lack = [k for k in REQUIRED if k not in c]
        if lack:
            raise SystemExit("error: %s: claim %s: missing %s" % (path, c.get("id", "?"), ", ".join(lack)))
        for key in ("inside", "outside"):
            if c["verdict"].get(key) not in R.OUTCOMES:
                raise SystemExit("error: %s: claim %s: verdict.%s must be one of %s" % (
                    path, c["id"], key, ", ".join(R.OUTCOMES)))
        odd = set(c.get("requires", {})) - REQUIRES
        if odd:
            raise SystemExit("error: %s: claim %s: requires.%s (allowed: %s)" % (
                path, c["id"], ", ".join(sorted(odd)), ", ".join(sorted(REQUIRES))))
        head, _, n = c["rule"].partition("/")
        if head != c["id"] or not n.isdigit():
            raise SystemExit("error: %s: claim %s: rule %r must be %s/N" % (path, c["id"], c["rule"], c["id"]))
        for h in c.get("history", []):
            lack = [k for k in ("rule", "registered", "text", "verdict", "data") if k not in h]
            # An engine entry (`engine` = the version that gave the verdict) or a rerun entry
            # (`rerun` = the tables that changed it) keeps the rule's id: the engine or the data
            # changed, not the rule.
            if "engine" in h and not isinstance(h["engine"], int):
                raise SystemExit("error: %s: claim %s: history entry %s: engine must be a version number" % (
                    path, c["id"], h.get("rule", "?")))
            if "rerun" in h and (not isinstance(h["rerun"], str) or not h["rerun"].strip()):
                raise SystemExit("error: %s: claim %s: history entry %s: rerun must name the tables" % (
                    path, c["id"], h.get("rule", "?")))
            if lack or (h["rule"] == c["rule"] and "engine" not in h and "rerun" not in h):
                raise SystemExit("error: %s: claim %s: history entry %s: %s" % (
                    path, c["id"], h.get("rule", "?"),
                    "missing " + ", ".join(lack) if lack else "has the current rule's id"))
        if c["statistic"] not in KINDS:
            raise SystemExit("error: %s: claim %s: statistic %r (allowed: %s)" % (
                path, c["id"], c["statistic"], ", ".join(sorted(KINDS))))
        if c["id"] in ids:
            raise SystemExit("error: %s: claim id %s twice" % (path, c["id"]))
        ids.add(c["id"])


def variant(claim, beside):
    """The claim with a [[claim.beside]] entry's overrides (select merged, accounting/quantity
    replaced), applied to the claim and to each of its series."""
    def over(d):
        d = dict(d)
        if "select" in beside:
            d["select"] = {**d.get("select", {}), **beside["select"]}
        if "quantity" in beside:
            d["quantity"] = beside["quantity"]
        return d
    v = over(claim)
    if "accounting" in beside:
        v["accounting"] = beside["accounting"]
    if "series" in claim:
        v["series"] = [over(s) for s in claim["series"]]
    return v


def needs_of(v, ctx):
    """What the tables lack for this rule: its [claim.requires] and, for a timed accounting, runs."""
    srcs = claims_measures.sources_of(v)
    needs = requirement_needs(v.get("requires", {}), ctx.tables, srcs, v.get("select"))
    if ctx.accountings.get(v["accounting"], {}).get("timed"):
        needs += runs_needs(ctx.tables, srcs, ctx.defaults["min_runs_timed"])
    return needs


def measure(v, ctx):
    """The kind's result, with anything it found missing added to its needs."""
    try:
        m = KINDS[v["statistic"]](v, ctx)
    except Missing as e:
        return claims_measures.Measured([], [str(e)], [])
    return m


MARK = {R.INSIDE: "", R.OUTSIDE: " (outside)", R.UNDECIDED: " (undecided)"}


def one_unit(u):
    """A judged unit's text: label, measurement, and whether it lies outside or is undecided."""
    return "%s%s%s" % (u.label + ": " if u.label else "", u.text, MARK[u.judgement])


def every_unit(units, prefix=""):
    """One text per judged unit, each with its judgement and reason (results/claims.toml `units`)."""
    return ["%s%s%s" % (prefix, one_unit(u), " — " + u.reason if u.reason else "") for u in units]


def units_text(units):
    """The measured text of judged units: every unit when few, else counts and those not inside."""
    one = one_unit
    if len(units) <= UNITS_LISTED:
        return "; ".join(one(u) for u in units)
    inside = [u for u in units if u.judgement == R.INSIDE]
    rest = [u for u in units if u.judgement != R.INSIDE]
    head = "%d units: %d inside, %d outside, %d undecided" % (
        len(units), len(inside), sum(u.judgement == R.OUTSIDE for u in units),
        sum(u.judgement == R.UNDECIDED for u in units))
    shown = rest[:UNITS_LISTED - 2] + inside[:max(2, UNITS_LISTED - len(rest))]
    more = len(units) - len(shown)
    return head + " — " + "; ".join(one(u) for u in shown) + ("; … %d more" % more if more else "")


def beside_text(claim, ctx, shown):
    """Each [[claim.beside]] variant's units, and what it needs beyond the needs already `shown`;
    and every unit of every variant, one text each, named by the variant."""
    parts, lines = [], []
    for b in claim.get("beside", []):
        v = variant(claim, b)
        needs = needs_of(v, ctx)
        m = measure(v, ctx)
        body = units_text(m.units) if m.units else ""
        lack = [n for n in dict.fromkeys(needs + m.needs) if n not in shown]
        tail = ("needs " + "; needs ".join(lack)) if lack else ""
        parts.append("%s — %s" % (b["label"], "; ".join(x for x in (body, tail) if x)))
        lines += every_unit(m.units, "beside: %s — " % b["label"])
    return parts, lines


def timing_text(claim, ctx):
    """Where seconds were taken, for every accounting of the claim that is timed."""
    used = [claim["accounting"]] + [b.get("accounting") for b in claim.get("beside", [])]
    if not any(ctx.accountings.get(a, {}).get("timed") for a in used if a):
        return ""
    out = []
    for name in claims_measures.sources_of(claim):
        meta = os.path.join(ctx.tables.results, name, "%s.meta.toml" % name)
        if not os.path.exists(meta):
            continue
        with open(meta, "rb") as f:
            run = tomllib.load(f)
        cores = run["run"].get("other_cores", math.nan)
        quiet = cores == cores and cores <= BUSY_CORES
        out.append("%s: %s, %d thread(s), other processes %.2f cores%s, %d run(s)" % (
            name, run["machine"]["cpu"], run["run"]["threads"], cores,
            "" if quiet else " (busy machine: seconds unreliable)", ctx.tables.n_runs(name)))
    return "seconds — " + "; ".join(out) if out else ""


def registered_text(claim, ctx):
    commit = ctx.commits.get(claim["registered"])
    return claim["registered"] + (", " + commit[:SHORT_HASH] if commit else "")


def earlier_text(claim):
    def one(h):
        engine = ", claims engine %d" % h["engine"] if "engine" in h else ""
        rerun = ", before the rerun on %s" % h["rerun"] if "rerun" in h else ""
        return "%s%s%s (%s, on the %s tables): %s" % (h["rule"], engine, rerun, h["registered"], h["data"],
                                                     h["verdict"])
    return "; ".join(one(h) for h in claim.get("history", []))


def judge(claim, ctx):
    """One claim: its record for claims.toml and the README (`registered`: the rule's date and the
    commit that registered it, from the pre-registration's `commits`)."""
    needs = needs_of(claim, ctx)
    m = measure(claim, ctx)
    outcome, reason = R.outcome(m.units, claim["verdict"], needs + m.needs)
    measured = [units_text(m.units)] if m.units else ["nothing measured"]
    measured += m.notes
    absent = optional_missing(claim.get("requires", {}), ctx.tables, claims_measures.sources_of(claim),
                              claim.get("select"))
    if absent:
        measured.append("not in the tables (optional): " + "; ".join(absent))
    beside, beside_units = beside_text(claim, ctx, needs + m.needs)
    measured += ["beside: " + t for t in beside]
    for d in claim.get("derived", []):
        try:
            measured.append(DERIVED[d["kind"]](d, ctx))
        except Missing as e:
            measured.append("%s: needs %s" % (d["kind"], e))
    srcs = [s for s in claims_measures.sources_of(claim) if ctx.tables.exists(s)] or claims_measures.sources_of(claim)
    note = "; ".join(x for x in (claim["note"], timing_text(claim, ctx)) if x)
    return dict(id=claim["id"], claim=claim["claim"], reference=claim["reference"], paper=claim["paper"],
                source="%s/%s.csv" % (srcs[0], srcs[0]), headline=m.headline or "nothing measured",
                measured=" · ".join(measured), units=every_unit(m.units) + beside_units,
                verdict="%s: %s" % (outcome, reason), outcome=outcome, rule=claim["rule"],
                registered=registered_text(claim, ctx), accounting=claim["accounting"], earlier=earlier_text(claim),
                note=note)


# ----------------------------------------------------------------------------------------------
# output


def toml_str(s):
    return '"%s"' % s.replace("\\", "\\\\").replace('"', '\\"')


def render_toml(records, engine=None):
    lines = ["# The claims of both papers and what raycost measured for each. Written by",
             "# scripts/claims.py from the committed tables and claims/preregistered.toml; do not edit",
             "# by hand (CI checks it).", ""]
    if engine is not None:
        lines += ["# The claims engine's version (claims/engine-versions.toml) that judged them.",
                  "engine = %d" % engine, ""]
    for c in records:
        lines.append("[[claim]]")
        for k in ("claim", "reference", "paper", "source", "headline", "measured", "verdict", "outcome", "rule",
                  "accounting", "earlier", "note"):
            if c[k]:
                lines.append("%s = %s" % (k, toml_str(c[k])))
        if c["units"]:
            lines.append("units = [")
            lines += ["  %s," % toml_str(u) for u in c["units"]]
            lines.append("]")
        lines.append("")
    return "\n".join(lines)


def cell(text):
    return text.replace("|", "\\|")


def render_table(records):
    """README's claims table: one line a claim — the claim (linked to its section of DOC) and its
    source in the paper, the paper's number, the measured headline, the verdict, the table."""
    rows = ["| claim (source) | paper says | raycost measured (95 % CI) | verdict | table |",
            "|---|---|---|---|---|"]
    for c in records:
        name = c["source"].split("/")[0]
        rows.append("| [%s](%s#%s) (%s) | %s | %s | **%s** | [%s](results/%s) |" % (
            cell(c["claim"]), DOC, c["id"], cell(c["reference"]), cell(c["paper"]), cell(c["headline"]),
            c["outcome"], name, c["source"]))
    return "\n".join(rows)


def md(text):
    """A text from the tables as Markdown shows it literally (no emphasis, no HTML)."""
    return text.replace("\\", "\\\\").replace("*", "\\*").replace("<", "&lt;").replace("|", "\\|")


def render_doc(records):
    """DOC: one section per claim (its id the heading, README's rows link to it) with the verdict's
    reason, the rule, what is shown beside, and every judged unit."""
    out = ["# The claims of both papers: every unit", "",
           "<!-- Written by scripts/claims.py from results/claims.toml; do not edit by hand: "
           "python3 scripts/claims.py --check (CI) fails on any change. -->", "",
           "README.md's claims table gives one line a claim: the paper's number, the measured headline "
           "and the verdict. This page gives, for each claim, the verdict's reason, the rule that decided it "
           "(registered before the data in [claims/preregistered.toml](../claims/preregistered.toml); "
           "[claims/README.md](../claims/README.md) explains the statistics and outcomes), what is measured "
           "beside it, and every judged unit with its 95 % interval. Machine-readable: "
           "[results/claims.toml](../results/claims.toml).", ""]
    for c in records:
        out += ["## %s" % c["id"], "", "**%s** (%s)" % (md(c["claim"]), md(c["reference"])), "",
                "- paper: %s" % md(c["paper"]),
                "- measured: %s" % md(c["headline"]),
                "- verdict: **%s** — %s" % (c["outcome"], md(c["verdict"].split(": ", 1)[1])),
                "- rule: %s (%s) · accounting %s" % (c["rule"], md(c["registered"]), c["accounting"])]
        if c["earlier"]:
            out.append("- earlier: %s" % md(c["earlier"]))
        out += ["- table: [%s](../results/%s)" % (c["source"].split("/")[0], c["source"]),
                "- method: %s" % md(c["note"]), "", "Measured (as the report shows it):", ""]
        out += ["- %s" % md(p) for p in c["measured"].split(" · ")]
        if c["units"]:
            out += ["", "Every unit (%d):" % len(c["units"]), ""]
            out += ["%d. %s" % (i + 1, md(u)) for i, u in enumerate(c["units"])]
        out.append("")
    return "\n".join(out)


def records_of(toml_path, pre):
    """The records as results/claims.toml holds them, with what the pre-registration adds (the
    claim's id from its rule, the rule's date and commit): README's table and DOC are rendered
    from them, so a test can hold both against the committed file without judging anything."""
    with open(toml_path, "rb") as f:
        stored = tomllib.load(f).get("claim", [])
    by_id = {c["id"]: c for c in pre["claim"]}
    commits = pre.get("commits", {})
    out = []
    for c in stored:
        cid = c["rule"].split("/")[0]
        p = by_id.get(cid)
        reg = p["registered"] if p else ""
        rec = {k: c.get(k, "") for k in ("claim", "reference", "paper", "source", "headline", "measured", "verdict",
                                          "outcome", "rule", "accounting", "earlier", "note")}
        rec.update(id=cid, units=c.get("units", []),
                   registered=reg + (", " + commits[reg][:SHORT_HASH] if reg in commits else ""))
        out.append(rec)
    return out


def collect(results, prereg_path):
    return judge_all(results, load(prereg_path))


def judge_all(results, pre):
    """Every claim of a (checked) pre-registration against the tables under `results`."""
    ctx = Context(Tables(results), pre)
    return [judge(c, ctx) for c in pre["claim"]]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="fail if the committed files differ")
    ap.add_argument("--results", default=os.path.join(ROOT, "results"), help="the results folder")
    ap.add_argument("--prereg", default=os.path.join(ROOT, "claims", "preregistered.toml"))
    ap.add_argument("--print", action="store_true", help="print each claim's outcome and write nothing")
    args = ap.parse_args()
    pre = load(args.prereg)
    records = judge_all(args.results, pre)
    if args.print:
        for c in records:
            print("%-24s %-14s %s" % (c["id"], c["outcome"], c["verdict"].split(": ", 1)[1]))
        return 0
    versions = V.read_ledger()
    digest = V.engine_hash()
    new_versions = V.updated(versions, records, digest)
    ledger_text = V.render_ledger(new_versions)
    problems = V.transition_problems(new_versions, pre)
    toml_text = render_toml(records, new_versions[-1]["version"])
    readme_path = os.path.join(ROOT, "README.md")
    readme = open(readme_path).read()
    if BEGIN not in readme or END not in readme:
        raise SystemExit("error: README.md has no %s … %s markers" % (BEGIN, END))
    a, rest = readme.split(BEGIN, 1)
    _, b = rest.split(END, 1)
    new_readme = a + BEGIN + "\n" + render_table(records) + "\n" + END + b
    doc_path = os.path.join(ROOT, DOC)
    doc_text = render_doc(records)
    old_doc = open(doc_path).read() if os.path.exists(doc_path) else ""
    toml_path = os.path.join(args.results, "claims.toml")
    old_toml = open(toml_path).read() if os.path.exists(toml_path) else ""
    for p in problems:
        print("error: %s" % p, file=sys.stderr)
    if args.check:
        if not versions or versions[-1]["hash"] != digest:
            print("error: the claims engine (%s) changed since its version %d in %s: run python3 scripts/claims.py "
                  "to record the next version" % (", ".join(V.ENGINE_FILES), len(versions),
                                                  os.path.relpath(V.LEDGER, ROOT)), file=sys.stderr)
            return 1
        old_ledger = open(V.LEDGER).read()
        bad = [n for n, old, new in (("results/claims.toml", old_toml, toml_text),
                                     ("README.md's claims table", readme, new_readme),
                                     (DOC, old_doc, doc_text),
                                     (os.path.relpath(V.LEDGER, ROOT), old_ledger, ledger_text)) if old != new]
        if bad:
            print("error: %s differ(s) from the committed tables: run python3 scripts/claims.py" % " and ".join(bad),
                  file=sys.stderr)
            return 1
        if problems:
            return 1
        print("claims: %d claims, README and results/claims.toml match the tables (claims engine %d)"
              % (len(records), new_versions[-1]["version"]))
        return 0
    if problems:
        print("error: nothing written: a verdict changed with the engine or with new tables; keep the earlier "
              "one in the claim's history (claims/README.md)", file=sys.stderr)
        return 1
    open(V.LEDGER, "w").write(ledger_text)
    open(toml_path, "w").write(toml_text)
    open(readme_path, "w").write(new_readme)
    open(doc_path, "w").write(doc_text)
    for c in records:
        print("%-24s %s" % (c["id"], c["outcome"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
