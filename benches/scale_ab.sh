#!/usr/bin/env bash
# The scale bench's BVH figures for two builds of its binary, alternated run by run.
#
#   bash benches/scale_ab.sh BASELINE_BINARY NEW_BINARY [PAIRS] > ab.txt    # 4 pairs by default
#   python3 benches/scale_ab.py ab.txt                                        # medians, B/A
#
# Each run is `<binary> --bench` with SCALE_SIZES=1e5,1e6 SCALE_ROUNDS=2 SCALE_RENDER=0 (set
# SCALE_SIZES to change the sizes; SCALE_PYTHON as for the bench: without embreex the Embree
# columns are left out), niced, the baseline (A) first in every pair. Printed per run: its
# start, the load average before and after it, and the bench's build, memory and one-thread
# lines. Compare the medians of A and B (the bench's figures are CPU time: they hold better
# than wall time on a shared machine, not against other processes sharing the caches).
set -euo pipefail
export LC_ALL=C
if [ $# -lt 2 ]; then
  echo "usage: bash benches/scale_ab.sh BASELINE_BINARY NEW_BINARY [PAIRS]" >&2
  exit 2
fi
a=$(realpath "$1")
b=$(realpath "$2")
pairs=${3:-4}
export SCALE_SIZES=${SCALE_SIZES:-1e5,1e6} SCALE_ROUNDS=2 SCALE_RENDER=0
for i in $(seq "$pairs"); do
  for v in A B; do
    bin=$a
    [ "$v" = B ] && bin=$b
    start=$(date +%T)
    l0=$(cut -d' ' -f1 /proc/loadavg)
    out=$(nice "$bin" --bench 2>&1) || {
      echo "error: $bin --bench failed:" >&2
      echo "$out" | tail -5 >&2
      exit 1
    }
    l1=$(cut -d' ' -f1 /proc/loadavg)
    echo "=== $v pair $i $start load $l0-$l1"
    echo "$out" | grep -E 'triangles$|build:|memory:|/1 ' || {
      echo "error: no figures in the output of $bin --bench" >&2
      exit 1
    }
  done
done
