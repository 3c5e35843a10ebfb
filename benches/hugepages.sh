#!/usr/bin/env bash
# Resident memory and the part of it in transparent huge pages (AnonHugePages) of a command
# and of its child processes, sampled every half second from /proc/<pid>/smaps_rollup while it
# runs (Linux). For the scale bench: which side's BVH memory huge pages back, ours or Embree's
# (its Python child).
#
#   bash benches/hugepages.sh <command> [args...] > samples.txt
#
# One line per process and sample: time, pid, name, Rss and AnonHugePages in kB. The
# command's own output goes to stderr.
set -uo pipefail
"$@" 1>&2 &
root=$!
while kill -0 "$root" 2>/dev/null; do
  for p in $root $(pgrep -P "$root"); do
    f=/proc/$p/smaps_rollup
    [ -r "$f" ] || continue
    rss=$(awk '/^Rss:/ {print $2}' "$f")
    huge=$(awk '/^AnonHugePages:/ {print $2}' "$f")
    echo "$(date +%T.%N | cut -c1-10) $p $(cat /proc/"$p"/comm 2>/dev/null) $rss $huge"
  done
  sleep 0.5
done
wait "$root"
