#!/usr/bin/env python3
"""Every committed result can be rerun from its metadata: runs `raycost reproduce DIR --check` (which
checks the spec and its keys' defaults against the recorded spec hash, every input file's content and
the point count — a crossover's input files — and runs nothing) on each result folder under results/
(NAME/ and NAME/runs/R/) whose metadata records command run, merge or crossover. A result the check
refuses must be listed in .ci/known-stale-results.txt (awaiting a rerun on the current code); a
listed one that the check accepts, or that no longer exists, fails too, so the list only shrinks.

Usage: python3 scripts/check_rerunnable_results.py --raycost target/release/raycost [--results DIR]
       [--allow FILE]   (CI runs it)
"""

import argparse
import os
import subprocess
import sys
import tomllib

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
RERUNNABLE = ("run", "merge", "crossover")


def result_folders(results, root=ROOT):
    """Folders (relative to the repository root) holding one result's metadata of a rerunnable
    command, sorted; a folder of several runs' shards is skipped (its merged result is checked)."""
    out = []
    for d, _, files in os.walk(results):
        metas = [f for f in files if f.endswith(".meta.toml") and ".shard-" not in f]
        if not metas:
            continue
        meta = "crossover.meta.toml" if "crossover.meta.toml" in metas else sorted(metas)[0]
        with open(os.path.join(d, meta), "rb") as fh:
            command = tomllib.load(fh).get("run", {}).get("command", "")
        if command in RERUNNABLE:
            out.append(os.path.relpath(d, root))
    return sorted(out)


def read_allow(path):
    """The allow-list's folders (comments and blank lines skipped)."""
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [line.split("#")[0].strip().rstrip("/") for line in f
                if line.strip() and not line.lstrip().startswith("#")]


def check(raycost, folder, root=ROOT):
    """(rerunnable, the check's last line)."""
    p = subprocess.run([raycost, "reproduce", folder, "--check"], cwd=root, capture_output=True, text=True)
    last = (p.stdout + p.stderr).strip().splitlines()
    return p.returncode == 0, (last[-1] if last else "exit %d" % p.returncode)


def problems(raycost, results, allow_path, root=ROOT):
    """(errors, stale, folders): a refused result not listed, a listed one rerunnable now or gone
    are errors; refused listed ones are the stale ones."""
    allowed = read_allow(allow_path)
    folders = result_folders(results, root)
    listed_in = os.path.relpath(allow_path, root)
    errors, stale = [], []
    for f in folders:
        ok, line = check(raycost, f, root)
        if ok and f in allowed:
            errors.append("%s: listed in %s but rerunnable now: remove the line" % (f, listed_in))
        elif not ok and f not in allowed:
            errors.append("%s: cannot be rerun as recorded: %s" % (f, line))
        elif not ok:
            stale.append(f)
    for a in allowed:
        if a not in folders:
            errors.append("%s: listed in %s but no such result: remove the line" % (a, listed_in))
    return errors, stale, folders


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--raycost", required=True)
    ap.add_argument("--results", default=os.path.join(ROOT, "results"))
    ap.add_argument("--allow", default=os.path.join(ROOT, ".ci", "known-stale-results.txt"))
    args = ap.parse_args()
    errors, stale, folders = problems(os.path.abspath(args.raycost), args.results, args.allow)
    for s in stale:
        print("known stale, awaiting a rerun on the current code: %s" % s)
    for e in errors:
        print("error: %s" % e, file=sys.stderr)
    if errors:
        print("error: every committed result must rerun from its metadata (`raycost reproduce DIR`); rerun it "
              "on the current code, or list it in .ci/known-stale-results.txt until then", file=sys.stderr)
        return 1
    print("results: %d rerunnable as recorded, %d known stale awaiting a rerun" % (len(folders) - len(stale), len(stale)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
