#!/usr/bin/env bash
# ci_test.sh — the real Slurm test of sharded sweeps and `raycost merge`, run by .ci/run.
#
#   RAYCOST=target/release/raycost bash scripts/slurm/ci_test.sh
#
# Starts a private one-node Slurm cluster (cluster.sh up: installs slurmctld/slurmd/munge with
# apt-get if missing), submits tests/specs/slurm-sweep.toml (8 points) as a job array of 4 shards
# plus the dependent merge job (submit.sh --wait, which prints the squeue/scontrol/sacct lines and
# checks every task completed 0:0), runs the same spec locally without shards, and compares the
# merged table with the local one: every non-timing column byte for byte, and the histogram table
# whole. The cluster is always brought down again (trap), by the pids cluster.sh recorded.
#
# Then the same with one run's photons split: tests/specs/slurm-photons.toml as
# an array of PHOTON_SHARDS tasks (`submit.sh --photons`: task K runs `--photon-shard
# K/PHOTON_SHARDS`) and the dependent merge, compared with a local unsplit run: every non-timing
# column of every table (main, points; a quasi-static run's frames) byte for byte; then the same
# for a quasi-static run's photons, tests/specs/slurm-photons-qs.toml (objects moving over four
# frames). For the first, a shard file is then deleted: the merge must name it, `submit.sh --check`
# list it, and `submit.sh --missing` rerun just it before the merge gives the same table again.
#
# Builds nothing. Environment: RAYCOST (default target/release/raycost in the repository), SPEC
# (default tests/specs/slurm-sweep.toml), SHARDS (default 4), PHOTON_SPEC (default
# tests/specs/slurm-photons.toml), QS_PHOTON_SPEC (default tests/specs/slurm-photons-qs.toml),
# PHOTON_SHARDS (default 3), RAYCOST_SLURM_* (see cluster.sh).
# Exit codes: 0 passed, or skipped because Slurm cannot be made available here (a line
# "SKIP slurm: <reason>"); 1 failed.
set -euo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
RAYCOST=${RAYCOST:-$ROOT/target/release/raycost}
SPEC=${SPEC:-$ROOT/tests/specs/slurm-sweep.toml}
SHARDS=${SHARDS:-4}
PHOTON_SPEC=${PHOTON_SPEC:-$ROOT/tests/specs/slurm-photons.toml}
PHOTON_SHARDS=${PHOTON_SHARDS:-3}
QS_PHOTON_SPEC=${QS_PHOTON_SPEC:-$ROOT/tests/specs/slurm-photons-qs.toml}

say() { printf 'slurm: %s\n' "$*"; }
fail() { printf 'slurm: FAIL: %s\n' "$*" >&2; exit 1; }

[[ $RAYCOST == */* ]] || RAYCOST=$(command -v "$RAYCOST" || true)
[[ -x $RAYCOST ]] || fail "RAYCOST=$RAYCOST is not an executable (build it first: cargo build --release)"
RAYCOST=$(realpath "$RAYCOST")
[[ -f $SPEC ]] || fail "spec $SPEC: no such file"
[[ -f $PHOTON_SPEC ]] || fail "spec $PHOTON_SPEC: no such file"
[[ -f $QS_PHOTON_SPEC ]] || fail "spec $QS_PHOTON_SPEC: no such file"
command -v python3 >/dev/null 2>&1 || fail "python3 is needed for the table comparison"

work=$(mktemp -d "${TMPDIR:-/tmp}/raycost-slurm-ci.XXXXXX")
cluster_started=0
finish() {
    local rc=$?
    if [[ $cluster_started -eq 1 ]]; then
        if [[ $rc -ne 0 ]]; then
            # Whatever the jobs said, for the CI log.
            for f in "$work"/slurm/slurm-logs/*.out; do
                [[ -s $f ]] || continue
                printf -- '--- %s ---\n' "$f" >&2
                tail -n 20 "$f" >&2
            done
        fi
        bash "$HERE/cluster.sh" down || { echo "slurm: cluster.sh down failed" >&2; [[ $rc -ne 0 ]] || rc=1; }
    fi
    if [[ $rc -eq 0 ]]; then rm -rf "$work"; else echo "slurm: files kept in $work" >&2; fi
    exit "$rc"
}
trap finish EXIT
trap 'exit 130' INT TERM

# --- cluster -------------------------------------------------------------------------------
rc=0
bash "$HERE/cluster.sh" up 2>"$work/up.err" || rc=$?
cat "$work/up.err" >&2
if [[ $rc -eq 3 ]]; then
    reason=$(sed -n 's/^cluster.sh: unavailable: //p' "$work/up.err" | tail -n 1)
    echo "SKIP slurm: ${reason:-cluster.sh up said Slurm is unavailable here}"
    exit 0
fi
cluster_started=1 # from here on, bring it down whatever happens (up also stops a half-started one)
[[ $rc -eq 0 ]] || fail "cluster.sh up failed (exit $rc)"
eval "$(bash "$HERE/cluster.sh" env)"
say "cluster up: $(sinfo -h -o '%P %D nodes %c CPUs %T' | head -n 1) (SLURM_CONF=$SLURM_CONF)"

# --- the sweep as a job array, merged by the dependent job -----------------------------------
spec_name() { # experiment.name of a spec file
    awk '
    /^[[:space:]]*\[/ { section = $0; gsub(/[[:space:]]/, "", section); next }
    section == "[experiment]" && /^[[:space:]]*name[[:space:]]*=/ {
        sub(/^[^=]*=[[:space:]]*/, ""); sub(/[[:space:]]*(#.*)?$/, "")
        gsub(/^["\047]|["\047]$/, ""); print; exit
    }' "$1"
}
name=$(spec_name "$SPEC")
points=$("$RAYCOST" check "$SPEC" | sed -n 's/.*, \([0-9][0-9]*\) point(s),.*/\1/p')
[[ -n $name && -n $points ]] || fail "could not read experiment.name and the point count of $SPEC"
[[ $points -ge 8 ]] || fail "$SPEC has $points points; the test needs at least 8"
say "submitting $SPEC ($name, $points points) as an array of $SHARDS tasks + merge"
t0=$SECONDS
RAYCOST=$RAYCOST bash "$HERE/submit.sh" --wait --timeout 900 "$SPEC" "$SHARDS" "$work/slurm" ||
    fail "submit.sh --wait failed"
say "array and merge done in $((SECONDS - t0)) s"
merged=$work/slurm/$name
for k in $(seq 0 $((SHARDS - 1))); do
    f=$merged/$name.shard-$k-of-$SHARDS.csv
    [[ -s $f ]] || fail "array task $k wrote no $f"
    say "task $k: $(($(wc -l <"$f") - 1)) points in $(basename "$f"), host $(sed -n 's/^host = "\(.*\)"/\1/p' "$merged/$name.shard-$k-of-$SHARDS.meta.toml")"
done
for log in "$work"/slurm/slurm-logs/*.out; do sed 's/^/  log: /' "$log"; done

# --- the same spec locally, unsharded; compare -------------------------------------------------
"$RAYCOST" run "$SPEC" --out "$work/local" --quiet
python3 - "$merged/$name.csv" "$work/local/$name/$name.csv" "$merged/$name.hist.csv" "$work/local/$name/$name.hist.csv" "$merged/$name.meta.toml" "$SHARDS" "$points" <<'EOF'
import csv, sys, tomllib

merged, local, mhist, lhist, mmeta, shards, points = sys.argv[1:]
shards, points = int(shards), int(points)

with open(mmeta, "rb") as f:
    meta = tomllib.load(f)
# Column classes come from the run's metadata (declared with each column), never from a name.
classes = {c["name"]: c["class"] for c in meta["columns"]["main"]}

def timing(col):
    return classes[col] == "timing"

def table(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]

hm, rm = table(merged)
hl, rl = table(local)
if hm != hl:
    sys.exit(f"slurm: FAIL: headers differ:\n  merged {hm}\n  local  {hl}")
if len(rm) != points or len(rl) != points:
    sys.exit(f"slurm: FAIL: {len(rm)} merged rows, {len(rl)} local rows, expected {points}")
keep = [i for i, c in enumerate(hm) if not timing(c)]
bad = [(n, hm[i], a[i], b[i]) for n, (a, b) in enumerate(zip(rm, rl)) for i in keep if a[i] != b[i]]
if bad:
    for n, c, a, b in bad[:10]:
        print(f"slurm: row {n} column {c}: merged {a!r}, local {b!r}", file=sys.stderr)
    sys.exit(f"slurm: FAIL: {len(bad)} measured cells differ")
if [r[0] for r in rm] != [str(i) for i in range(points)]:
    sys.exit("slurm: FAIL: merged rows are not in point order")
with open(mhist, "rb") as a, open(lhist, "rb") as b:
    if a.read() != b.read():
        sys.exit("slurm: FAIL: merged hist table differs from the local one")
got = [s["run"]["shard"] for s in meta["shards"]]
if got != [f"{k}/{shards}" for k in range(shards)]:
    sys.exit(f"slurm: FAIL: merged metadata lists shards {got}")
print(f"slurm: {len(keep)} measured columns of {len(hm)} compared byte for byte; hist table identical; "
      f"merged meta lists {shards} shards on {sorted({s['machine']['host'] for s in meta['shards']})}")
print(f"slurm: merged table identical to local run ({points} points)")
EOF

# --- one run's photons as a job array, merged by the dependent job ------------------------------
photon_array() { # SPEC: its photons as PHOTON_SHARDS array tasks + merge, against a local run
    local spec=$1 pname pmerged k
    pname=$(spec_name "$spec")
    [[ -n $pname ]] || fail "could not read experiment.name of $spec"
    say "submitting $spec ($pname) as $PHOTON_SHARDS photon shards + merge"
    t0=$SECONDS
    RAYCOST=$RAYCOST bash "$HERE/submit.sh" --wait --timeout 900 --photons "$spec" "$PHOTON_SHARDS" "$work/photons-$pname" ||
        fail "submit.sh --wait --photons $spec failed"
    say "photon array and merge done in $((SECONDS - t0)) s"
    pmerged=$work/photons-$pname/$pname
    for k in $(seq 0 $((PHOTON_SHARDS - 1))); do
        [[ -s $pmerged/$pname.photon-shard-$k-of-$PHOTON_SHARDS.json ]] || fail "photon task $k wrote no shard file"
    done
    "$RAYCOST" run "$spec" --out "$work/plocal-$pname" --quiet
    compare_photons "$pmerged" "$work/plocal-$pname/$pname" "$pname"
    [[ ${2:-} == rerun-missing ]] || return 0
    # An incomplete set: shard 1's file lost (a task killed at its time limit). The merge names it,
    # submit.sh --check lists it, --missing reruns just it, and the merge of the whole set follows.
    rm -f "$pmerged/$pname.photon-shard-1-of-$PHOTON_SHARDS.json" "$pmerged/$pname".csv "$pmerged/$pname".*.csv "$pmerged/$pname.meta.toml"
    local err check rc=0
    err=$("$RAYCOST" merge "$pmerged" 2>&1) && fail "the merge of an incomplete set succeeded"
    [[ $err == *"photon shard(s) 1 of $PHOTON_SHARDS missing"* ]] || fail "the merge did not name the missing shard: $err"
    check=$(RAYCOST=$RAYCOST bash "$HERE/submit.sh" --check --photons "$spec" "$PHOTON_SHARDS" "$work/photons-$pname" 2>/dev/null) || rc=$?
    [[ $rc -eq 1 && $check == "MISSING=1" ]] || fail "submit.sh --check said '$check' (exit $rc), expected MISSING=1 (exit 1)"
    say "merge and submit.sh --check name missing photon shard 1; resubmitting just it"
    RAYCOST=$RAYCOST bash "$HERE/submit.sh" --wait --timeout 900 --missing --photons "$spec" "$PHOTON_SHARDS" "$work/photons-$pname" ||
        fail "submit.sh --wait --missing --photons $spec failed"
    compare_photons "$pmerged" "$work/plocal-$pname/$pname" "$pname"
}

compare_photons() { # MERGED_DIR LOCAL_DIR NAME: every non-timing cell of every table equal
    python3 - "$@" <<'EOF'
import csv, sys, tomllib

merged, local, name = sys.argv[1:]
with open(f"{merged}/{name}.meta.toml", "rb") as f:
    meta = tomllib.load(f)

def table(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]

# Every table the merged run declares (main, points, frames). Column classes come from the merged
# run's metadata: there the segment index's own work of a quasi-static run (each shard searched an
# index of its own segments) is classed timing, beside the seconds.
compared, tables = 0, []
for table_name, declared in meta["columns"].items():
    suffix = "csv" if table_name == "main" else f"{table_name}.csv"
    classes = {c["name"]: c["class"] for c in declared}
    hm, rm = table(f"{merged}/{name}.{suffix}")
    hl, rl = table(f"{local}/{name}.{suffix}")
    if hm != hl or len(rm) != len(rl) or not rm:
        sys.exit(f"slurm: FAIL: {name}.{suffix}: headers or row counts differ ({len(rm)} vs {len(rl)} rows)")
    keep = [i for i, c in enumerate(hm) if classes[c] != "timing"]
    bad = [(n, hm[i], a[i], b[i]) for n, (a, b) in enumerate(zip(rm, rl)) for i in keep if a[i] != b[i]]
    if bad:
        for n, c, a, b in bad[:10]:
            print(f"slurm: {suffix} row {n} column {c}: merged {a!r}, local {b!r}", file=sys.stderr)
        sys.exit(f"slurm: FAIL: {len(bad)} measured cells of {name}.{suffix} differ")
    compared += len(keep) * len(rm)
    tables.append(table_name)
print(f"slurm: photon-sharded {name} identical to the unsplit run ({compared} measured cells; tables {', '.join(tables)})")
EOF
}
photon_array "$PHOTON_SPEC" rerun-missing
photon_array "$QS_PHOTON_SPEC"
