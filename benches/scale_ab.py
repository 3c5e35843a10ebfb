"""Medians of `benches/scale_ab.sh`'s output: per size and figure, A's and B's values, their
ratio to Embree (loop cost out) where the run had Embree, the medians and B/A.

    python3 benches/scale_ab.py ab.txt
"""

import collections
import re
import statistics
import sys

values = collections.defaultdict(list)
ratios = collections.defaultdict(list)
side = size = None
for line in open(sys.argv[1]):
    m = re.match(r"=== (\w) pair (\d+) (\S+) load (\S+)", line)
    if m:
        side = m.group(1)
        print(f"{side} pair {m.group(2)} at {m.group(3)}, load {m.group(4)}")
        continue
    m = re.match(r"(\d+) triangles", line)
    if m:
        size = int(m.group(1))
        continue
    m = re.match(r"\s+(\S+/1)\s+([\d.]+) M.*?(?:\(([\d.]+)x\))?$", line)
    if m:
        values[(size, m.group(1), side)].append(float(m.group(2)))
        if m.group(3):
            ratios[(size, m.group(1), side)].append(float(m.group(3)))
        continue
    m = re.match(r"\s+build: ([\d.]+) s wall, ([\d.]+) s CPU", line)
    if m:
        values[(size, "build wall s", side)].append(float(m.group(1)))
        values[(size, "build CPU s", side)].append(float(m.group(2)))
        continue
    m = re.match(r"\s+memory: (\d+) bytes/triangle", line)
    if m:
        values[(size, "bytes/triangle", side)].append(float(m.group(1)))

for size, key in sorted({(s, k) for (s, k, _) in values}):
    a, b = values[(size, key, "A")], values[(size, key, "B")]
    if not a or not b:
        continue
    ma, mb = statistics.median(a), statistics.median(b)
    ra, rb = ratios[(size, key, "A")], ratios[(size, key, "B")]
    extra = f"; vs Embree A {ra} B {rb}" if ra else ""
    print(f"{size:>8} {key:17} A {a} med {ma:.3f} | B {b} med {mb:.3f} | B/A {mb / ma:.3f}{extra}")
