#!/usr/bin/env bash
# Smoke test of the plotting layer (CI): install the Python requirements, run the quickstart
# experiment with few rays into a temporary directory, plot it, and fail if the PNG is missing.
# Usage: scripts/check_plots.sh        (binary from $RAYCOST, default target/release/raycost)
set -euo pipefail

cd "$(dirname "$0")/.."
RAYCOST="${RAYCOST:-target/release/raycost}"
PYTHON="${PYTHON:-python3}"

if [ ! -x "$RAYCOST" ]; then
    echo "error: $RAYCOST: no such executable (build with cargo build --release or set RAYCOST)" >&2
    exit 2
fi

"$PYTHON" -m pip install -q -r scripts/requirements.txt

TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT

"$RAYCOST" run experiments/quickstart.toml --out "$TMP" --quiet --set experiment.rays=2000
CSV="$TMP/quickstart/quickstart.csv"
PNG="$TMP/quickstart/quickstart.png"
test -s "$CSV" || { echo "error: $CSV was not written" >&2; exit 1; }

MPLBACKEND=Agg "$PYTHON" scripts/plot_quickstart.py --input "$CSV"
if [ ! -s "$PNG" ]; then
    echo "error: $PNG was not written" >&2
    exit 1
fi
echo "ok: $PNG"
