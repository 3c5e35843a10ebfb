#!/usr/bin/env bash
# Photons per CPU second of the SPPM photon pass on the Cornell box, for two builds side by side.
#
#   bash benches/photon_rate.sh BASELINE_BINARY NEW_BINARY        # ROUNDS=3 by default
#   SCENE=examples/goblet.scn bash benches/photon_rate.sh A B      # another scene
#
# Method (the one benches/pbrt_compare/run.sh uses against pbrt): whole renders of SCENE with
# 4 iterations of 100 000 and of 1 100 000 photons, depth 16 (the scene's default), 1 thread,
# seed 1; parsing, set-up and the first camera pass are the same in both renders, so
# photons/s = 4e6 / (time of the large render - time of the small one). Each render is timed
# by wall clock and by CPU (user + system) time; the CPU figure is the one that holds on a
# shared machine. Two radii: the scene's file as it is (the default initial radius, 1.5 pixel
# footprints at each first hit) and with `radius 0.0111` (one pixel footprint at the back
# wall, the radius of benches/pbrt_compare). Every round runs both builds, the baseline first
# in odd rounds and second in even ones: compare the two builds within a round.
#
# The difference is not the photon pass alone: SPPM's camera pass also traces extra camera
# samples in proportion to the photon pass's ray casts (src/integrators/sppm/balance.rs), so
# part of the extra time is camera paths. `cargo bench --bench instructions` (photon-pass
# mode, under callgrind) counts the photon pass's own instructions per photon.
set -euo pipefail
export LC_ALL=C
if [ $# -ne 2 ]; then
  echo "usage: bash benches/photon_rate.sh BASELINE_BINARY NEW_BINARY" >&2
  exit 2
fi
base=$(realpath "$1")
new=$(realpath "$2")
cd "$(dirname "$0")/.."
scene=${SCENE:-examples/cornell.scn}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# The scene with a fixed radius: `radius` added to its `settings` block.
sed 's/settings {/settings { radius 0.0111 /' "$scene" > "$out/fixed.scn"
grep -q 'radius 0.0111' "$out/fixed.scn" || {
  echo "error: $scene has no 'settings {' to add the radius to" >&2
  exit 1
}

# Prints "wall cpu" in seconds for one render; stops the script if it fails.
timed() {
  local bin=$1 file=$2 photons=$3 t
  TIMEFORMAT='%R %U %S'
  if ! t=$( { time "$bin" render "$file" --integrator sppm --iterations 4 --photons "$photons" --threads 1 \
    --seed 1 -o "$out/image.exr" > "$out/last.log" 2>&1; } 2>&1); then
    echo "error: $bin render $file --photons $photons failed" >&2
    tail -n 20 "$out/last.log" >&2
    exit 1
  fi
  awk '{ printf "%.3f %.3f", $1, $2 + $3 }' <<< "$t"
}

# Prints "wall-rate cpu-rate" in M photons/s for one build and one scene file.
rate() {
  local bin=$1 file=$2 small large
  small=$(timed "$bin" "$file" 100000)
  large=$(timed "$bin" "$file" 1100000)
  awk -v s="$small" -v l="$large" 'BEGIN {
    split(s, a, " "); split(l, b, " ");
    printf "%.2f %.2f", 4 / (b[1] - a[1]), 4 / (b[2] - a[2]) }'
}

printf '%-6s %-16s %-10s %-10s %-10s %-10s %s\n' round radius "base wall" "base CPU" \
  "new wall" "new CPU" "new/base CPU"
for round in $(seq "${ROUNDS:-3}"); do
  for variant in default fixed; do
    file=$scene
    [ "$variant" = fixed ] && file=$out/fixed.scn
    if [ $((round % 2)) -eq 1 ]; then
      b=$(rate "$base" "$file")
      n=$(rate "$new" "$file")
    else
      n=$(rate "$new" "$file")
      b=$(rate "$base" "$file")
    fi
    label=$([ "$variant" = fixed ] && echo "0.0111" || echo "default (1.5 px)")
    awk -v r="$round" -v l="$label" -v b="$b" -v n="$n" 'BEGIN {
      split(b, x, " "); split(n, y, " ");
      printf "%-6s %-16s %-10s %-10s %-10s %-10s %.2fx\n", r, l, x[1], x[2], y[1], y[2], y[2] / x[2] }'
  done
done
echo "(M photons per second of wall / CPU time; 4e6 photons over the difference of two renders)"
