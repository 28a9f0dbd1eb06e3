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

# Every DETP plot script on a small fresh run of its own spec (fewer rays and points: the shape of
# the figure, not its statistics). detp-engines-cost keeps two of its sizes per axis.
for name in lines-rays-per-level lines-cache-misses sphere-cache-q detp-engines-cost detp-accuracy cornell-levels \
            detp-hard-cases; do
    case "$name" in
        lines-rays-per-level) args=(--set detp.points=2000 --set detp.replicas=2) ;;
        lines-cache-misses) args=(--set detp.points=5000 --set detp.chunk_points=5000) ;;
        sphere-cache-q) args=(--set detp.points=2000 --set detp.replicas=1) ;;
        detp-engines-cost) args=() ;;
        # A set key is no longer swept: one photon count, the other keys' sweeps kept.
        detp-accuracy) args=(--set detp.replicas=1) ;;
        cornell-levels) args=(--set detp.point_spacing=40 --set detp.replicas=1) ;;
        detp-hard-cases) args=(--set detp.replicas=2) ;;
    esac
    spec="experiments/$name.toml"
    if [ "$name" = detp-engines-cost ]; then
        # A smaller sweep of the same shape: two sizes per axis.
        sed -e 's/^"detp.photons" = .*/"detp.photons" = [8192, 16384]/' \
            -e 's/^"detp.points" = .*/"detp.points" = [500, 2000]/' "$spec" > "$TMP/$name.toml"
        spec="$TMP/$name.toml"
    elif [ "$name" = detp-accuracy ] || [ "$name" = cornell-levels ]; then
        args+=(--set detp.photons=5000)
    else
        args+=(--set detp.photons=16384)
    fi
    "$RAYCOST" run "$spec" --out "$TMP" --quiet "${args[@]}"
    MPLBACKEND=Agg "$PYTHON" "scripts/plot_${name//-/_}.py" --input "$TMP/$name/$name.csv"
    test -s "$TMP/$name/$name.png" || { echo "error: $name.png was not written" >&2; exit 1; }
    echo "ok: $name.png"
done

# The quasi-static plot scripts on small fresh runs of their specs (few photons and frames, coarse
# points); the kitchen ones read the vendored experiments/scenes/bart/.
for name in quasi-static-frames quasi-static-crossover quasi-static-static-points real-scene-levels \
            predict-engine quasi-static-robots; do
    case "$name" in
        quasi-static-frames) args=(--set detp.photons=5000 --set dynamic.frames=6 --set dynamic.check_every=2
                                   --set detp.point_spacing=40) ;;
        quasi-static-crossover) args=(--set detp.photons=5000 --set dynamic.frames=2 --set detp.point_spacing=40) ;;
        quasi-static-static-points) args=(--set detp.photons=5000 --set dynamic.frames=3 --set dynamic.check_every=1) ;;
        real-scene-levels) args=(--set detp.photons=5000 --set detp.point_spacing=0.3 --set detp.replicas=1) ;;
        quasi-static-robots) args=(--set detp.photons=5000 --set dynamic.frames=4 --set detp.point_spacing=4) ;;
        predict-engine) args=(--set detp.photons=5000 --set detp.point_spacing=40) ;;
    esac
    spec="experiments/$name.toml"
    "$RAYCOST" run "$spec" --out "$TMP" --quiet "${args[@]}"
    MPLBACKEND=Agg "$PYTHON" "scripts/plot_${name//-/_}.py" --input "$TMP/$name/$name.csv"
    test -s "$TMP/$name/$name.png" || { echo "error: $name.png was not written" >&2; exit 1; }
    echo "ok: $name.png"
done

# Speed against error against the path-traced reference, both scenes: two small photon counts (the
# d and k sweeps kept), a few reference paths per point, coarse Cornell points.
for name in speed-vs-error speed-vs-error-cornell; do
    sed -e 's/^"detp.photons" = .*/"detp.photons" = [5000, 20000]/' "experiments/$name.toml" > "experiments/.check-$name.toml"
    args=(--set detp.reference_samples=8)
    if [ "$name" = speed-vs-error-cornell ]; then
        args+=(--set detp.point_spacing=120)
    fi
    "$RAYCOST" run "experiments/.check-$name.toml" --out "$TMP" --quiet "${args[@]}"
    rm -f "experiments/.check-$name.toml"
    MPLBACKEND=Agg "$PYTHON" "scripts/plot_${name//-/_}.py" --input "$TMP/$name/$name.csv"
    test -s "$TMP/$name/$name.png" || { echo "error: $name.png was not written" >&2; exit 1; }
    echo "ok: $name.png"
done
