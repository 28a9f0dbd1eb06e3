#!/usr/bin/env bash
# Runs every committed spec (experiments/*.toml) with one raycost binary at a reduced size, so that
# two binaries (e.g. before and after a refactor) can be compared table by table with
# scripts/compare_tables.py:
#
#   scripts/parity_runs.sh OLD_BINARY /tmp/parity/old
#   scripts/parity_runs.sh target/release/raycost /tmp/parity/new
#   python3 scripts/compare_tables.py /tmp/parity/old /tmp/parity/new
#
# Each spec keeps every engine, side table and code path it exercises (replicas ≥ 2 where the spec
# has several, one replica where a spec's single-replica path matters, every sweep axis) and only
# shrinks its rays, photons, points, frames and reference samples, so that each run takes seconds.
# `--full NAME…` runs the named specs at their committed size instead.
#
# Across a change of the random streams (every measured column moves), build the new source with the
# old streams and compare that with the old binary: equal tables mean nothing but the stream changed.
# For the switch from ChaCha8 to Philox2x64 (src/sample/rng.rs):
#
#   cargo build --release --features chacha-streams && cp target/release/raycost /tmp/raycost-chacha
#   scripts/parity_runs.sh OLD_BINARY /tmp/parity/old
#   scripts/parity_runs.sh /tmp/raycost-chacha /tmp/parity/chacha
#   python3 scripts/compare_tables.py /tmp/parity/old /tmp/parity/chacha   # must be all equal
#
# And to see that the new streams give the same results in distribution (no byte equality possible):
#
#   scripts/parity_runs.sh target/release/raycost /tmp/parity/new
#   python3 scripts/compare_tables.py --stream-changed 4 /tmp/parity/old /tmp/parity/new
#
# (parameters equal, every X_mean within 4 combined SE of the old one). A later change compares as
# before: both binaries on the default (Philox) streams, byte for byte.
set -euo pipefail
# The sweep values ([a,b]) are not file patterns.
set -f

bin=${1:?usage: parity_runs.sh RAYCOST_BINARY OUT_DIR [--full NAME...]}
out=${2:?usage: parity_runs.sh RAYCOST_BINARY OUT_DIR [--full NAME...]}
shift 2
full=()
if [ "${1:-}" = "--full" ]; then
  shift
  full=("$@")
fi
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
: >"$out/warnings.log"

# name | the --set flags that shrink it (one per line in the array below)
specs=(
  "cornell-levels|detp.photons=20000 detp.replicas=2"
  "detp-accuracy|sweep.\"detp.photons\"=[2000,5000] detp.replicas=2"
  "detp-engines-cost|sweep.\"detp.photons\"=[4096,16384] sweep.\"detp.points\"=[100,1000,3000] detp.replicas=2"
  "detp-hard-cases|detp.photons=20000 detp.reference_samples=64 detp.replicas=2"
  "grid-cell-width|experiment.rays=4000"
  "grid-concentration|experiment.rays=4000 sweep.\"scene.spheres\"=[100,1000,10000]"
  "grid-cost-model|experiment.rays=4000 scene.spheres=20000 sweep.\"grid.cell_width\"=[0.3,1.0,2.0]"
  "grid-first-hit|experiment.rays=20000"
  "grid-radius-classes|experiment.rays=4000"
  "grid-scaling|experiment.rays=4000 sweep.\"scene.spheres\"=[100,1000,10000,100000]"
  "lines-cache-misses-unsorted|detp.photons=16384 detp.replicas=2"
  "lines-cache-misses|detp.photons=16384 sweep.\"detp.points\"=[2000,5000] detp.replicas=2"
  "lines-rays-per-level|detp.photons=32768 detp.points=2000 detp.replicas=2"
  "predict-engine|detp.photons=20000 detp.replicas=2"
  "quasi-static-amortisation|sweep.\"detp.photons\"=[10000,20000] detp.replicas=2"
  "quasi-static-crossover|detp.photons=10000 detp.replicas=2 sweep.\"dynamic.ratio\"=[0.2,0.35,0.55]"
  "quasi-static-frames|detp.photons=20000 dynamic.frames=4 dynamic.check_every=2 detp.replicas=2"
  "quasi-static-robots|detp.photons=20000 dynamic.frames=4 dynamic.check_every=2 detp.replicas=2"
  "quasi-static-static-points|detp.photons=20000 detp.replicas=2"
  "quickstart|experiment.rays=5000"
  "real-scene-levels|detp.photons=20000 detp.replicas=2"
  "render-cornell|detp.photons=20000 dynamic.frames=3 detp.write_points=true"
  "render-kitchen|detp.photons=20000 dynamic.frames=3 dynamic.reference_photons=20000"
  "speed-vs-error-cornell|sweep.\"detp.photons\"=[5000,20000] detp.reference_samples=64 detp.replicas=1"
  "speed-vs-error|sweep.\"detp.photons\"=[5000,20000] detp.reference_samples=64 detp.replicas=2"
  "sphere-cache-q|detp.photons=32768 detp.points=3000 detp.replicas=2"
  "theorem1-decomposition|detp.photons=32768 detp.points=1000 detp.replicas=2"
)

listed=()
for entry in "${specs[@]}"; do
  name=${entry%%|*}
  sets=${entry#*|}
  listed+=("$name")
  args=()
  size="reduced"
  if [ ${#full[@]} -gt 0 ]; then
    case " ${full[*]} " in
      *" $name "*) size="full" ;;
      *) continue ;;
    esac
  fi
  if [ "$size" = "reduced" ]; then
    for s in $sets; do args+=(--set "$s"); done
  fi
  start=$(date +%s.%N)
  "$bin" run "$root/experiments/$name.toml" --out "$out" --force --quiet "${args[@]}" 2>>"$out/warnings.log"
  printf '%-30s %-8s %6.1f s  %s\n' "$name" "$size" "$(echo "$(date +%s.%N) - $start" | bc)" "${args[*]}"
done

set +f
# Every committed spec must be listed above (a new spec without a reduced size is an error here).
for f in "$root"/experiments/*.toml; do
  n=$(basename "$f" .toml)
  case " ${listed[*]} " in
    *" $n "*) ;;
    *) echo "experiments/$n.toml has no entry in scripts/parity_runs.sh" >&2; exit 1 ;;
  esac
done
