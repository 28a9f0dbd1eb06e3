#!/usr/bin/env bash
# Regenerates every committed result: runs each experiment spec into results/ (replacing what is
# there) and draws its plot. Usage: scripts/run_experiments.sh [NAME...]   (default: all)
set -euo pipefail
cd "$(dirname "$0")/.."
RAYCOST="${RAYCOST:-target/release/raycost}"
PYTHON="${PYTHON:-python3}"
names=("$@")
if [ ${#names[@]} -eq 0 ]; then
  names=(quickstart grid-cell-width grid-first-hit grid-radius-classes grid-scaling grid-concentration grid-cost-model)
fi
for name in "${names[@]}"; do
  extra=()
  # Timed per-ray costs are cleanest on one thread (in-thread time is reported either way).
  [ "$name" = grid-cost-model ] && extra=(--threads 1)
  echo "== $name"
  "$RAYCOST" run "experiments/$name.toml" --out results --force "${extra[@]}"
  script="scripts/plot_${name//-/_}.py"
  MPLBACKEND=Agg "$PYTHON" "$script" --input "results/$name/$name.csv"
done
