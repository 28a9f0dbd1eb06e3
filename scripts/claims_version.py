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
        lines.append("[version.claims]")
        for cid, c in v["claims"].items():
            lines.append("%s = { rule = %s, outcome = %s }" % (_q(cid), _q(c["rule"]), _q(c["outcome"])))
        lines.append("")
    return "\n".join(lines)


def claims_of(records):
    """{claim id: {rule, outcome}} of claims.py's records."""
    return {r["id"]: {"rule": r["rule"], "outcome": r["outcome"]} for r in records}


def updated(versions, records, digest, where=""):
    """The ledger after judging `records` with the engine of hash `digest`: the newest version's
    outcomes replaced if the engine is unchanged, else a new version appended."""
    versions = [dict(v) for v in versions]
    now = claims_of(records)
    if versions and versions[-1]["hash"] == digest:
        versions[-1]["claims"] = now
    else:
        versions.append({"version": len(versions) + 1, "hash": digest, "where": where, "claims": now})
    return versions


def transition_problems(versions, prereg):
    """Every claim whose outcome changed between consecutive versions under the same rule id,
    without a history entry {rule, engine = the earlier version, verdict = its outcome}: one line
    each, naming the entry to add."""
    by_id = {c["id"]: c for c in prereg["claim"]}
    out = []
    for old, new in zip(versions, versions[1:]):
        for cid, was in old["claims"].items():
            now = new["claims"].get(cid)
            if now is None or now["rule"] != was["rule"] or now["outcome"] == was["outcome"]:
                continue
            history = by_id.get(cid, {}).get("history", [])
            if not any(h.get("engine") == old["version"] and h.get("rule") == was["rule"]
                       and h.get("verdict", "").split(":")[0].strip() == was["outcome"] for h in history):
                out.append("claim %s: engine %d gave %s, engine %d gives %s under the same rule %s: "
                           "add a [[claim.history]] entry with rule = %r, engine = %d, verdict = %r"
                           % (cid, old["version"], was["outcome"], new["version"], now["outcome"],
                              was["rule"], was["rule"], old["version"], was["outcome"]))
    return out
