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

import shrinking_list

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


def check(raycost, folder, root=ROOT):
    """(rerunnable, the check's last line)."""
    p = subprocess.run([raycost, "reproduce", folder, "--check"], cwd=root, capture_output=True, text=True)
    last = (p.stdout + p.stderr).strip().splitlines()
    return p.returncode == 0, (last[-1] if last else "exit %d" % p.returncode)


def problems(raycost, results, allow_path, root=ROOT):
    """(errors, stale, folders): a refused result not listed, a listed one rerunnable now or gone
    are errors; refused listed ones are the stale ones (each with the check's reason)."""
    folders = result_folders(results, root)
    refused = {}
    for f in folders:
        ok, line = check(raycost, f, root)
        if not ok:
            refused[f] = "%s: cannot be rerun as recorded: %s" % (f, line)
    errors, stale = shrinking_list.judge(refused, shrinking_list.read(allow_path), lambda f: f in folders,
                                         os.path.relpath(allow_path, root), "rerunnable now")
    return errors, stale, folders


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--raycost", required=True)
    ap.add_argument("--results", default=os.path.join(ROOT, "results"))
    ap.add_argument("--allow", default=os.path.join(ROOT, ".ci", "known-stale-results.txt"))
    args = ap.parse_args()
    errors, stale, folders = problems(os.path.abspath(args.raycost), args.results, args.allow)
    return shrinking_list.report(
        errors, stale, "known stale, awaiting a rerun on the current code",
        "every committed result must rerun from its metadata (`raycost reproduce DIR`); rerun it "
        "on the current code, or list it in .ci/known-stale-results.txt until then",
        "results: %d rerunnable as recorded, %d known stale awaiting a rerun" % (len(folders) - len(stale), len(stale)))


if __name__ == "__main__":
    sys.exit(main())
