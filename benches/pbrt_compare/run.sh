#!/usr/bin/env bash
# Photon-pass throughput of sppm-lang against pbrt's SPPM integrator on the same Cornell box.
#
# pbrt-v4 cannot be built on this project's machines (its source is on GitHub, which they
# cannot reach; no package registry ships it). The nearest SPPM that can be installed here is
# rs_pbrt (crates.io), a Rust port of pbrt-v3, whose SPPM is pbrt-v3's algorithm line by line
# (pbrt-v4's SPPM is the same algorithm). So this compares against that port, not pbrt-v4.
#
# Method, the same for both renderers: whole renders of examples/cornell.scn (and its pbrt
# twin, cornell.pbrt beside this file) with 4 iterations of 100 000 and of 1 100 000 photons,
# 1 thread. The time difference covers 4 000 000 photons and nothing else (parsing, set-up
# and the camera passes are the same in both renders), so photons/s = 4e6 / difference.
# Runs alternate between the renderers; machines are noisy, so compare within a round.
#
#   bash benches/pbrt_compare/run.sh            # ROUNDS=3 by default
#
# The first run installs rs_pbrt 0.9.12 into target/pbrt_compare (a few minutes on 2 cores).
set -euo pipefail
# EPOCHREALTIME (bash 5) prints the locale's decimal separator: keep it a point.
export LC_ALL=C
if [ -z "${EPOCHREALTIME:-}" ]; then
  echo "error: this script needs bash 5 or later (for EPOCHREALTIME)" >&2
  exit 1
fi
cd "$(dirname "$0")/../.."
root=$PWD
target=${CARGO_TARGET_DIR:-$root/target}
out=$target/pbrt_compare
mkdir -p "$out"
if ! [ -x "$out/bin/rs_pbrt" ]; then
  CARGO_TARGET_DIR="$out/build" cargo install rs_pbrt --version 0.9.12 --locked --root "$out"
fi
cargo build --release --locked
sppm=$target/release/sppm-lang
for photons in 100000 1100000; do
  sed "s/PHOTONS/$photons/" "$root/benches/pbrt_compare/cornell.pbrt" > "$out/cornell_$photons.pbrt"
done

seconds() { # prints the wall time of a command in seconds; stops the script if it fails
  local start=$EPOCHREALTIME
  if ! "$@" > "$out/last.log" 2>&1; then
    echo "error: failed: $*" >&2
    tail -n 20 "$out/last.log" >&2
    exit 1
  fi
  awk -v a="$start" -v b="$EPOCHREALTIME" 'BEGIN { print b - a }'
}
rate() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", 4 / (b - a) }'; }

cd "$out" # rs_pbrt writes its image into the working directory
for round in $(seq "${ROUNDS:-3}"); do
  p1=$(seconds "$out/bin/rs_pbrt" -t 1 -p "$out/cornell_100000.pbrt")
  p2=$(seconds "$out/bin/rs_pbrt" -t 1 -p "$out/cornell_1100000.pbrt")
  s1=$(seconds "$sppm" render "$root/examples/cornell.scn" --integrator sppm --iterations 4 --photons 100000 \
    --threads 1 --seed 1 -o "$out/sppm_100000.exr")
  s2=$(seconds "$sppm" render "$root/examples/cornell.scn" --integrator sppm --iterations 4 --photons 1100000 \
    --threads 1 --seed 1 -o "$out/sppm_1100000.exr")
  ratio=$(awk -v p="$(rate "$p1" "$p2")" -v q="$(rate "$s1" "$s2")" 'BEGIN { printf "%.1f", q / p }')
  printf 'round %s: rs_pbrt (pbrt-v3 SPPM) %s M photons/s, sppm-lang %s M photons/s: %sx (1 thread each)\n' \
    "$round" "$(rate "$p1" "$p2")" "$(rate "$s1" "$s2")" "$ratio"
done
