#!/usr/bin/env bash
# `sppm-lang check` of the generated 100 000-object scene against POV-Ray 3.7 parsing the same
# scene written in its language (benches/support/big_scene.rs). Both are whole processes under
# `/usr/bin/time -f '%U %S %M'`: CPU time (user + system) and peak resident memory. Runs
# alternate (RUNS of each, 5 unless set); the medians and both ratios are printed. POV-Ray's
# process parses, bounds and renders 1x1 pixel; its own "Parse Time" (wall) is printed beside.
#
# SPPM_BIN=path measures that binary instead of building `target/release/sppm-lang`;
# SPPM_SCENE_DIR=dir keeps the generated scenes there (made once, reused by later runs).
# Skips with a message when `povray` is not installed (Debian: apt-get install povray).
set -euo pipefail
if ! command -v povray >/dev/null 2>&1; then
    echo "povray is not installed: skipping the POV-Ray comparison (apt-get install -y povray)"
    exit 0
fi
if [ ! -x /usr/bin/time ]; then
    echo "/usr/bin/time is not installed: skipping (apt-get install -y time)"
    exit 0
fi
cd "$(dirname "$0")/.."
runs=${RUNS:-5}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
dir=${SPPM_SCENE_DIR:-$tmp}
if [ ! -s "$dir/big.scn" ] || [ ! -s "$dir/big.pov" ]; then
    SPPM_BIG_SCENE_DIR="$dir" cargo bench --quiet --bench parse >/dev/null
fi
target=${CARGO_TARGET_DIR:-target}
bin=${SPPM_BIN:-}
if [ -z "$bin" ]; then
    cargo build --release --quiet --bin sppm-lang
    bin=$target/release/sppm-lang
fi
ours_cpu=() ours_mem=() pov_cpu=() pov_mem=() pov_parse=()
for _ in $(seq "$runs"); do
    /usr/bin/time -o "$tmp/t" -f '%U %S %M' "$bin" check "$dir/big.scn" >/dev/null 2>&1
    ours_cpu+=("$(awk '{print $1 + $2}' "$tmp/t")")
    ours_mem+=("$(awk '{print $3 / 1024}' "$tmp/t")")
    /usr/bin/time -o "$tmp/t" -f '%U %S %M' \
        povray -D "+I$dir/big.pov" +W1 +H1 -F -GR +GS +WT1 2>"$tmp/pov.log" >/dev/null
    pov_cpu+=("$(awk '{print $1 + $2}' "$tmp/t")")
    pov_mem+=("$(awk '{print $3 / 1024}' "$tmp/t")")
    pov_parse+=("$(grep 'Parse Time' "$tmp/pov.log" | sed 's/.*(\([0-9.]*\) seconds).*/\1/')")
done
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR] = $1} END {
    print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
oc=$(median "${ours_cpu[@]}") om=$(median "${ours_mem[@]}")
pc=$(median "${pov_cpu[@]}") pm=$(median "${pov_mem[@]}") pp=$(median "${pov_parse[@]}")
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg); medians of $runs alternated runs"
printf 'sppm-lang check: %.2f s CPU, %.0f MiB peak (runs: %s s; %s MiB)\n' "$oc" "$om" \
    "${ours_cpu[*]}" "$(printf '%.0f ' "${ours_mem[@]}")"
printf 'POV-Ray 3.7:     %.2f s CPU, %.0f MiB peak (runs: %s s; %s MiB); its Parse Time %s s\n' \
    "$pc" "$pm" "${pov_cpu[*]}" "$(printf '%.0f ' "${pov_mem[@]}")" "$pp"
awk -v oc="$oc" -v om="$om" -v pc="$pc" -v pm="$pm" 'BEGIN {
    printf "ratio check / POV-Ray: CPU %.2f x, peak memory %.2f x (goal: at most 2 x)\n",
        oc / pc, om / pm }'
