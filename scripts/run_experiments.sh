#!/usr/bin/env bash
# Regenerates every committed result: runs each experiment spec into results/ (replacing what is
# there) and draws its plot, then prints a table of each experiment's wall time and the total.
# Usage: scripts/run_experiments.sh [NAME...]   (default: all)
set -euo pipefail
cd "$(dirname "$0")/.."
RAYCOST="${RAYCOST:-target/release/raycost}"
PYTHON="${PYTHON:-python3}"
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  names=(quickstart grid-cell-width grid-first-hit grid-radius-classes grid-scaling grid-concentration grid-cost-model
         lines-rays-per-level lines-cache-misses-unsorted lines-cache-misses sphere-cache-q detp-engines-cost
         detp-accuracy cornell-levels quasi-static-frames quasi-static-crossover quasi-static-static-points
         quasi-static-amortisation real-scene-levels speed-vs-error speed-vs-error-cornell predict-engine quasi-static-robots
         theorem1-decomposition detp-hard-cases quasi-static-lines)
fi
secs=()
failed=""
total_start=$(date +%s)
# The table, also when a run fails part-way: the experiments done so far and the one that failed.
summary() {
  local rc=$? i sum=0
  [ ${#secs[@]} -eq 0 ] && [ -z "$failed" ] && return "$rc"
  echo
  echo "== wall time per experiment (raycost run; plots not included)"
  printf '%-32s %10s\n' experiment seconds
  for i in "${!secs[@]}"; do
    printf '%-32s %10d\n' "${names[$i]}" "${secs[$i]}"
    sum=$(( sum + secs[i] ))
  done
  if [ "$rc" -ne 0 ] && [ -n "$failed" ]; then printf '%-32s %10s\n' "$failed" "failed"; fi
  printf '%-32s %10d\n' "total (${#secs[@]} of ${#names[@]} experiments)" "$sum"
  printf '%-32s %10d\n' "wall time, plots included" "$(( $(date +%s) - total_start ))"
  return "$rc"
}
trap summary EXIT
for name in "${names[@]}"; do
  extra=()
  # Timed per-ray costs are cleanest on one thread (in-thread time is reported either way).
  [ "$name" = grid-cost-model ] && extra=(--threads 1)
  # Theorem 1 is fitted to times: one thread, so small points (one chunk) and large ones run alike.
  [ "$name" = detp-engines-cost ] && extra=(--threads 1)
  echo "== $name"
  start=$(date +%s)
  failed="$name"
  "$RAYCOST" run "experiments/$name.toml" --out results --force "${extra[@]}"
  secs+=("$(( $(date +%s) - start ))")
  echo "== $name: ${secs[-1]} s"
  failed="$name (plot)"
  # The unsorted cache-miss baseline is drawn by plot_lines_cache_misses.py with the sorted runs.
  [ "$name" = lines-cache-misses-unsorted ] && continue
  script="scripts/plot_${name//-/_}.py"
  MPLBACKEND=Agg "$PYTHON" "$script" --input "results/$name/$name.csv"
done
failed=""
