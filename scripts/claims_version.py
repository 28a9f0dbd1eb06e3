"""The claims engine, versioned like a rule.

A rule that has judged data is never edited in place; neither is the engine that applies it
without a record. The engine's version is the hash of its source files (ENGINE_FILES); the ledger
claims/engine-versions.toml keeps one [[version]] per engine that has judged the committed tables:
its number, its hash, and every claim's rule and outcome under it. scripts/claims.py writes the
ledger: it updates the newest version's outcomes while the engine is unchanged (new tables), and
adds version N+1 when the engine's hash changed. Earlier versions are never rewritten.

When version N+1 gives a claim (under the same rule id) another outcome than version N did, the
earlier verdict must be kept in that claim's history in claims/preregistered.toml:

  [[claim.history]]
  rule = "CLAIM/K"          # the rule (the same id: the engine changed, not the rule)
  engine = 2                # the engine version that gave the earlier verdict
  registered = "…"          # where that engine is (commit)
  text = "what that engine did differently"
  verdict = "inconclusive"  # the outcome it gave
  data = "…"                # on which tables

Each version keeps the outcomes it gave when it was recorded (`[version.adopted]`, written only
where they differ from its latest ones): those were judged on the same tables as the version before
it ended with, so comparing the two isolates what the engine changed.

New tables can change a verdict too (a rerun; the engine unchanged). The newest version then keeps a
`[[version.rerun]]` record {claim, rule, was, now}, written by scripts/claims.py, and the earlier
verdict must be kept in the claim's history as a rerun entry (the rule id stays: the data changed,
not the rule):

  [[claim.history]]
  rule = "CLAIM/K"
  rerun = "…"               # the tables that changed it (commit, what was rerun and why)
  registered = "…"          # when the rule was registered
  text = "what the new tables differ in"
  verdict = "holds-in-part" # the outcome the earlier tables gave
  data = "…"                # the earlier tables

scripts/claims.py refuses to write, and `--check` (CI) fails, when such an entry is missing
(`transition_problems`), and `--check` fails when the engine's files no longer hash to the newest
version (the engine changed and its verdicts were not recorded).
"""

import hashlib
import os
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
LEDGER = os.path.join(ROOT, "claims", "engine-versions.toml")

# Every file whose code decides a verdict (the statistics library included: its intervals do).
ENGINE_FILES = ("claims.py", "claims_data.py", "claims_derived.py", "claims_engines.py",
                "claims_levels.py", "claims_measures.py", "claims_rules.py", "claims_version.py",
                "raycost_stats.py")


def engine_hash(folder=HERE, files=ENGINE_FILES):
    """sha256 over the engine's files (name and text, in this order), as hex."""
    h = hashlib.sha256()
    for name in files:
        with open(os.path.join(folder, name), "rb") as f:
            text = f.read().replace(b"\r\n", b"\n")
        h.update(name.encode() + b"\0" + text + b"\0")
    return h.hexdigest()


def read_ledger(path=LEDGER):
    """The ledger's versions, oldest first ([] without a ledger)."""
    if not os.path.exists(path):
        return []
    with open(path, "rb") as f:
        versions = tomllib.load(f).get("version", [])
    numbers = [v["version"] for v in versions]
    if numbers != list(range(1, len(numbers) + 1)):
        raise SystemExit("error: %s: versions must be 1, 2, … in order (got %s)" % (path, numbers))
    return versions


def _q(s):
    return '"%s"' % str(s).replace("\\", "\\\\").replace('"', '\\"')


def render_ledger(versions):
    lines = ["# The claims engine's versions (scripts/claims_version.py): one [[version]] per engine that",
             "# has judged the committed tables, with every claim's rule and outcome under it. Written by",
             "# scripts/claims.py; earlier versions are never rewritten. A changed outcome between two",
             "# versions needs a [[claim.history]] entry with `engine` = the earlier version in",
             "# claims/preregistered.toml.", ""]
    for v in versions:
        lines += ["[[version]]", "version = %d" % v["version"], "hash = %s" % _q(v["hash"])]
        if v.get("where"):
            lines.append("where = %s" % _q(v["where"]))
        for table in ("claims", "adopted"):
            if table in v:
                lines.append("[version.%s]" % table)
                lines += ["%s = { rule = %s, outcome = %s }" % (_q(cid), _q(c["rule"]), _q(c["outcome"]))
                          for cid, c in v[table].items()]
        for r in v.get("rerun", []):
            lines += ["[[version.rerun]]"] + ["%s = %s" % (k, _q(r[k])) for k in RERUN_KEYS]
        lines.append("")
    return "\n".join(lines)


# A verdict changed by new tables under one engine: which claim, under which rule, from what to what.
RERUN_KEYS = ("claim", "rule", "was", "now")


def claims_of(records):
    """{claim id: {rule, outcome}} of claims.py's records."""
    return {r["id"]: {"rule": r["rule"], "outcome": r["outcome"]} for r in records}


def updated(versions, records, digest, where=""):
    """The ledger after judging `records` with the engine of hash `digest`: the newest version's
    outcomes replaced if the engine is unchanged, else a new version appended."""
    versions = [dict(v) for v in versions]
    now = claims_of(records)
    if versions and versions[-1]["hash"] == digest:
        last = versions[-1]
        # New tables under the same engine: every changed outcome (same rule) is a rerun record;
        # the outcomes the version gave when it was recorded stay as `adopted`.
        reruns = [{"claim": cid, "rule": c["rule"], "was": last["claims"][cid]["outcome"], "now": c["outcome"]}
                  for cid, c in now.items()
                  if cid in last["claims"] and last["claims"][cid]["rule"] == c["rule"]
                  and last["claims"][cid]["outcome"] != c["outcome"]]
        if reruns:
            last["rerun"] = list(last.get("rerun", [])) + reruns
        if now != last["claims"]:
            last.setdefault("adopted", last["claims"])
            last["claims"] = now
        if last.get("adopted") == now:
            del last["adopted"]
    else:
        versions.append({"version": len(versions) + 1, "hash": digest, "where": where, "claims": now})
    return versions


def adopted(version):
    """The outcomes a version gave when it was recorded (on the tables the version before it ended with)."""
    return version.get("adopted", version["claims"])


def transition_problems(versions, prereg):
    """Every claim whose outcome changed between consecutive versions under the same rule id,
    without a history entry {rule, engine = the earlier version, verdict = its outcome}: one line
    each, naming the entry to add."""
    by_id = {c["id"]: c for c in prereg["claim"]}
    out = []
    for old, new in zip(versions, versions[1:]):
        for cid, was in old["claims"].items():
            now = adopted(new).get(cid)
            if now is None or now["rule"] != was["rule"] or now["outcome"] == was["outcome"]:
                continue
            history = by_id.get(cid, {}).get("history", [])
            if not any(h.get("engine") == old["version"] and h.get("rule") == was["rule"]
                       and h.get("verdict", "").split(":")[0].strip() == was["outcome"] for h in history):
                out.append("claim %s: engine %d gave %s, engine %d gives %s under the same rule %s: "
                           "add a [[claim.history]] entry with rule = %r, engine = %d, verdict = %r"
                           % (cid, old["version"], was["outcome"], new["version"], now["outcome"],
                              was["rule"], was["rule"], old["version"], was["outcome"]))
    return out + rerun_problems(versions, by_id)


def rerun_problems(versions, by_id):
    """Every verdict changed by new tables (a `[[version.rerun]]` record) without a rerun entry
    {rule, rerun, verdict = the earlier outcome} in its claim's history: as many entries as records."""
    out = []
    records = [r for v in versions for r in v.get("rerun", [])]
    for key in sorted({(r["claim"], r["rule"], r["was"]) for r in records}):
        cid, rule, was = key
        needed = sum(1 for r in records if (r["claim"], r["rule"], r["was"]) == key)
        history = by_id.get(cid, {}).get("history", [])
        kept = sum(1 for h in history if "rerun" in h and h.get("rule") == rule
                   and h.get("verdict", "").split(":")[0].strip() == was)
        if kept < needed:
            now = [r["now"] for r in records if (r["claim"], r["rule"], r["was"]) == key][-1]
            out.append("claim %s: new tables turned %s into %s under the same rule %s: add a [[claim.history]] "
                       "entry with rule = %r, rerun = \"the tables that changed it\", verdict = %r"
                       % (cid, was, now, rule, rule, was))
    return out
