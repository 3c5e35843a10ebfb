#!/usr/bin/env bash
# `sppm-lang check` of the generated 100 000-object scene against POV-Ray 3.7 parsing the same
# scene written in its language (benches/support/big_scene.rs). Runs alternate, 3 of each; the
# medians of CPU time (user + system) and the ratios are printed. POV-Ray's figures: its own
# "Parse Time" and the CPU time of the whole `povray` process (parse, bounding, a 1x1 render).
# Skips with a message when `povray` is not installed (Debian: apt-get install povray).
set -euo pipefail
if ! command -v povray >/dev/null 2>&1; then
    echo "povray is not installed: skipping the POV-Ray comparison (apt-get install -y povray)"
    exit 0
fi
cd "$(dirname "$0")/.."
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
cargo build --release --quiet
SPPM_BIG_SCENE_DIR="$dir" cargo bench --quiet --bench parse >/dev/null
bin=target/release/sppm-lang
TIMEFORMAT='%U %S %R'
ours=() povcpu=() povparse=()
for _ in 1 2 3; do
    t=$( { time "$bin" check "$dir/big.scn" >/dev/null 2>&1; } 2>&1 )
    ours+=("$(awk '{print $1 + $2}' <<<"$t")")
    t=$( { time povray -D "+I$dir/big.pov" +W1 +H1 -F -GR +GS +WT1 2>"$dir/pov.log"; } 2>&1 )
    povcpu+=("$(awk '{print $1 + $2}' <<<"$t")")
    povparse+=("$(grep 'Parse Time' "$dir/pov.log" | sed 's/.*(\([0-9.]*\) seconds).*/\1/')")
done
median() { printf '%s\n' "$@" | sort -g | sed -n 2p; }
o=$(median "${ours[@]}"); c=$(median "${povcpu[@]}"); p=$(median "${povparse[@]}")
echo "sppm-lang check, 100k objects: ${o} s CPU (median of 3)"
echo "POV-Ray 3.7: parse ${p} s (its Parse Time), whole process ${c} s CPU"
awk -v o="$o" -v p="$p" -v c="$c" 'BEGIN {
    printf "ratio: check / POV-Ray parse = %.2f; check / POV-Ray process = %.2f\n", o / p, o / c }'
