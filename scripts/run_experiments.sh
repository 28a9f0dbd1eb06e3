#!/usr/bin/env bash
# Regenerates every committed result: runs each experiment spec into results/ (replacing what is
# there) and draws its plot. Usage: scripts/run_experiments.sh [NAME...]   (default: all)
set -euo pipefail
cd "$(dirname "$0")/.."
RAYCOST="${RAYCOST:-target/release/raycost}"
PYTHON="${PYTHON:-python3}"
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  names=(quickstart grid-cell-width grid-first-hit grid-radius-classes grid-scaling grid-concentration grid-cost-model
         lines-rays-per-level lines-cache-misses-unsorted lines-cache-misses sphere-cache-q detp-engines-cost
         detp-accuracy cornell-levels quasi-static-frames quasi-static-crossover quasi-static-static-points
         real-scene-levels speed-vs-error predict-engine quasi-static-robots)
fi
for name in "${names[@]}"; do
  extra=()
  # Timed per-ray costs are cleanest on one thread (in-thread time is reported either way).
  [ "$name" = grid-cost-model ] && extra=(--threads 1)
  # Theorem 1 is fitted to times: one thread, so small points (one chunk) and large ones run alike.
  [ "$name" = detp-engines-cost ] && extra=(--threads 1)
  echo "== $name"
  start=$(date +%s)
  "$RAYCOST" run "experiments/$name.toml" --out results --force "${extra[@]}"
  echo "== $name: $(( $(date +%s) - start )) s"
  # The unsorted cache-miss baseline is drawn by plot_lines_cache_misses.py with the sorted runs.
  [ "$name" = lines-cache-misses-unsorted ] && continue
  script="scripts/plot_${name//-/_}.py"
  MPLBACKEND=Agg "$PYTHON" "$script" --input "results/$name/$name.csv"
done
