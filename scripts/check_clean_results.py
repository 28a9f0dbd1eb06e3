#!/usr/bin/env python3
"""Committed results come from clean builds: fails on any metadata under results/ (NAME.meta.toml,
crossover.meta.toml, those of separate runs) that records git_dirty = "true" — in its own [raycost]
table or in the inputs it records ([extra.*]) — unless it is listed in the allow-list of known
dirty results awaiting regeneration (.ci/known-dirty-results.txt). A listed file that is no longer
dirty, or no longer exists, fails too, so the list cannot go stale and only shrinks.

Usage: python3 scripts/check_clean_results.py [--results DIR] [--allow FILE]   (CI runs it)
"""

import argparse
import os
import sys
import tomllib

import shrinking_list

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def dirty_places(meta):
    """The tables of a parsed metadata file that say git_dirty = "true", as dotted names with the
    commit they name."""
    out = []

    def walk(t, name):
        if str(t.get("git_dirty", "")).lower() == "true":
            out.append("%s (commit %s)" % (name, t.get("git_commit", "?")))
        for k, v in t.items():
            if isinstance(v, dict):
                walk(v, "%s.%s" % (name, k) if name else k)
    walk(meta, "")
    return out


def dirty_results(results, root):
    """{path relative to root: [dirty places]} of every *.meta.toml below `results`."""
    found = {}
    for d, _, files in os.walk(results):
        for f in sorted(files):
            if not f.endswith(".meta.toml"):
                continue
            p = os.path.join(d, f)
            with open(p, "rb") as fh:
                places = dirty_places(tomllib.load(fh))
            if places:
                found[os.path.relpath(p, root)] = places
    return found


def problems(results, allow_path, root):
    """(errors, notes): unlisted dirty results and stale lines are errors; listed ones are notes."""
    refused = {p: "%s: git_dirty = \"true\" in %s" % (p, ", ".join(places))
               for p, places in dirty_results(results, root).items()}
    return shrinking_list.judge(refused, shrinking_list.read(allow_path),
                                lambda p: os.path.exists(os.path.join(root, p)),
                                os.path.relpath(allow_path, root), "is clean now")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--results", default=os.path.join(ROOT, "results"))
    ap.add_argument("--allow", default=os.path.join(ROOT, ".ci", "known-dirty-results.txt"))
    args = ap.parse_args()
    errors, notes = problems(args.results, args.allow, ROOT)
    return shrinking_list.report(
        errors, notes, "known dirty, awaiting regeneration",
        "committed results must come from a clean build of a commit on main (rerun them; "
        "a result awaiting that may be listed in .ci/known-dirty-results.txt)",
        "results: no dirty build outside the %d known awaiting regeneration" % len(notes))


if __name__ == "__main__":
    sys.exit(main())
