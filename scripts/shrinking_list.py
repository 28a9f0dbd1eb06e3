"""A list of known exceptions that may only shrink: what CI's result checks (committed results from
clean builds, committed results rerunnable from their metadata) share.

A check finds the items it refuses. Each refused item must be on the list (it awaits a rerun), and
each listed item must still be refused and still exist, or the line must go: so the list cannot go
stale, and an exception is never kept by accident after its cause is gone.
"""

import os
import sys


def read(path):
    """The list's entries: one per line, `#` starts a comment, blank lines skipped, a trailing `/`
    dropped (a folder may be written either way). A missing file is an empty list."""
    if not os.path.exists(path):
        return []
    with open(path) as f:
        entries = (line.split("#")[0].strip().rstrip("/") for line in f)
        return [e for e in entries if e]


def judge(refused, listed, exists, listed_in, fixed):
    """(errors, awaiting). `refused` maps each item the check refuses to the line that says why;
    an unlisted refused item is an error, a listed one is awaiting. A listed item the check no
    longer refuses is an error too: `fixed` says what it is now (e.g. "is clean now"), or it is
    named gone when `exists(item)` is false."""
    errors, awaiting = [], []
    for item, line in sorted(refused.items()):
        (awaiting if item in listed else errors).append(line)
    for item in listed:
        if item not in refused:
            now = fixed if exists(item) else "no longer exists"
            errors.append("%s: listed in %s but %s: remove the line" % (item, listed_in, now))
    return errors, awaiting


def report(errors, awaiting, awaiting_label, hint, summary):
    """Prints what awaits and the errors (with `hint`, what to do, after them) and returns the exit
    code: 1 on any error, else 0 after printing `summary`."""
    for a in awaiting:
        print("%s: %s" % (awaiting_label, a))
    for e in errors:
        print("error: %s" % e, file=sys.stderr)
    if errors:
        print("error: %s" % hint, file=sys.stderr)
        return 1
    print(summary)
    return 0
