#!/usr/bin/env bash
# Makes the report of a results folder in a temporary folder and opens it in a headless Chromium
# (scripts/report_browser_test.py): the page must load with no console error, no exception and no
# failed load, every <img> must decode, every claim's verdict cell must be coloured by its outcome,
# every measured cell must lie inside the 1280 px viewport, and a screenshot is written.
#
# Usage: scripts/report_browser_test.sh [RESULTS] [SCREENSHOT.png]
#   RESULTS     results folder (default: results)
#   SCREENSHOT  where the screenshot goes (default: a temporary file, printed)
# Environment: RAYCOST (the binary; default target/release/raycost), CHROME (the browser; default
# chromium on PATH).
set -euo pipefail
cd "$(dirname "$0")/.."
results=${1:-results}
raycost=${RAYCOST:-target/release/raycost}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
shot=${2:-$(mktemp --suffix=.png)}
"$raycost" report "$results" --out "$out"
claims=()
if [ -f "$results/claims.toml" ]; then claims=(--expect-claims); fi
python3 scripts/report_browser_test.py "$out/index.html" --screenshot "$shot" "${claims[@]}"
