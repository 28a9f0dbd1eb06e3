#!/usr/bin/env bash
# Statistical battery on raycost's random streams exactly as the engines key them: dieharder's full
# battery (`-a`, with `-Y 1 -k 2`: a WEAK p-value is retested on more samples until it resolves) on the
# raw 64-bit words of examples/rng_stream.rs.
#
#   scripts/rng_quality.sh [OUT_DIR] [MODE ...]     # default results/rng-quality, all modes
#
# Modes (see examples/rng_stream.rs): `photons 1` — the first word of streams keyed by consecutive
# photon ids, the hard case for a counter-based generator; `photons 4`; `interleave 16` — 16
# consecutive photons' first 64 words side by side; `seeds` — first words over consecutive seeds;
# `long` — one stream. Writes OUT_DIR/MODE.txt (dieharder's report) and OUT_DIR/summary.txt.
# dieharder comes from Debian (`apt-get install dieharder`; installed here when run as root).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/results/rng-quality}
shift || true
modes=("$@")
[ ${#modes[@]} -gt 0 ] || modes=("photons 1" "photons 4" "interleave 16" "seeds" "long")

if ! command -v dieharder >/dev/null; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq dieharder >/dev/null
  else
    echo "dieharder not found: apt-get install dieharder" >&2
    exit 2
  fi
fi
cd "$root"
# RNG_STREAM=PATH uses an already built examples/rng_stream binary.
gen=${RNG_STREAM:-}
if [ -z "$gen" ]; then
  cargo build --release --quiet --example rng_stream
  gen=$root/target/release/examples/rng_stream
fi
mkdir -p "$out"
# The final verdict of each (test, ntup): `-Y 1` appends the retests of a WEAK one, the last line wins.
final() {
  awk -F'|' 'NF >= 6 && $6 ~ /PASSED|WEAK|FAILED/ { k = $1 "|" $2; v = $6; gsub(/ /, "", v); if (!(k in a)) n++; a[k] = v }
    END { for (k in a) c[a[k]]++; printf "%d tests: PASSED %d, WEAK %d, FAILED %d", n, c["PASSED"], c["WEAK"], c["FAILED"] }' "$1"
}
for mode in "${modes[@]}"; do
  file="$out/$(echo "$mode" | tr ' ' '-').txt"
  start=$(date +%s)
  {
    echo "# $gen $mode | dieharder -g 200 -a -Y 1 -k 2"
    echo "# commit $(git rev-parse --short HEAD), $(dieharder -l | sed -n 2p | tr -s ' ' | sed 's/^# //; s/ #$//')"
    # dieharder reads until it has what it needs and then closes the pipe.
    # shellcheck disable=SC2086
    "$gen" $mode | dieharder -g 200 -a -Y 1 -k 2
  } >"$file" 2>&1 || true
  printf '%-16s %6d s  %s\n' "$mode" "$(($(date +%s) - start))" "$(final "$file")"
done | tee "$out/summary.txt"
