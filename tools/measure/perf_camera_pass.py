#!/usr/bin/env python3
"""Splits a `vcm` render's perf samples by the statement of `camera_path::radiance` they run
under, and the merges' samples into the grid query and the merge's body.

Input: the text of `perf script -F ip,sym,srcline` of a `perf record --call-graph dwarf` of a
release build (line tables on: the release profile keeps them), whose inlined frames carry
their source lines. A sample belongs to the camera pass when a frame of `radiance` in
camera_path.rs is on its stack; the outermost such frame's line is the statement of
`radiance` it runs under (the call of `merge`, `direct`, `connect`, `bounce`, the closest hit,
the BSDF set-up). Under the merge, a sample is the body's when a frame of `merge`'s closure
(camera_path.rs, within `merge`) is on it, else the grid query's. Each statement's samples are
also split by the first of these found on their stack: a shadow ray (`occluded`), a texture
lookup, the closest-hit traversal, a BSDF value or density, a light sample.

    perf script -i x.perf -F ip,sym,srcline > x.txt
    python3 tools/measure/perf_camera_pass.py x.txt --source src/integrators/vcm/camera_path.rs
"""

import argparse
import collections
import re

FRAME = re.compile(r"\s+[0-9a-f]+ (.*)$")
SRC = re.compile(r"(\S+?):(\d+)")

CATEGORIES = [
    ("shadow ray", ("occluded",)),
    ("textures", ("textures::",)),
    ("closest-hit traversal", ("intersect", "closest", "lathe", "bezier")),
    ("BSDF value or density", ("Bsdf::", "Lobes::", "materials::")),
    ("light sample", ("sample_light", "sample_toward", "lights::")),
]


def samples(path):
    """Each sample's frames, innermost first, as (symbol, file, line)."""
    with open(path, errors="replace") as f:
        lines = f.read().split("\n")
    cur, i = [], 0
    while i < len(lines):
        line = lines[i]
        if not line.strip():
            if cur:
                yield cur
                cur = []
            i += 1
            continue
        m = FRAME.match(line)
        if not m:
            i += 1
            continue
        src = ""
        if i + 1 < len(lines) and lines[i + 1].strip() and not FRAME.match(lines[i + 1]):
            src = lines[i + 1].strip()
            i += 1
        s = SRC.match(src)
        cur.append((m.group(1), s.group(1) if s else None, int(s.group(2)) if s else None))
        i += 1
    if cur:
        yield cur


def function_lines(source, name):
    """The first and last line of `fn name` in `source` (up to the next top-level item)."""
    text = open(source).read().split("\n")
    start = next(k for k, l in enumerate(text) if re.match(rf"(pub\S* )?fn {name}\b", l))
    end = next((k for k in range(start + 1, len(text)) if text[k].startswith("}")), len(text))
    return start + 1, end + 1, text


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("script", help="text of `perf script -F ip,sym,srcline`")
    ap.add_argument("--source", default="src/integrators/vcm/camera_path.rs")
    args = ap.parse_args()
    m_lo, m_hi, text = function_lines(args.source, "merge")
    total = camera = light = 0
    by_line = collections.Counter()
    cats = collections.defaultdict(collections.Counter)
    merge_query = merge_body = merge_wide = 0
    merge_call = None
    for s in samples(args.script):
        total += 1
        if any("LightPass" in sym and "run" in sym for sym, _, _ in s):
            light += 1
        idx = None
        for k, (sym, f, _) in enumerate(s):
            if f == "camera_path.rs" and ("radiance" in sym.split("<")[0]):
                idx = k
        if idx is None:
            continue
        camera += 1
        line = s[idx][2]
        by_line[line] += 1
        inner = [sym for sym, _, _ in s[:idx]]
        cat = next((c for c, keys in CATEGORIES if any(k in x for x in inner for k in keys)), "other")
        cats[line][cat] += 1
        if "merge(" in text[line - 1]:
            merge_call = line
            body = any(
                f == "camera_path.rs" and m_lo <= ln <= m_hi and "closure" in sym
                for sym, f, ln in s[:idx]
            )
            merge_body += body
            merge_query += not body
            merge_wide += any("wide" in sym for sym in inner)
    pct = lambda n: f"{100 * n / max(total, 1):.1f} %"
    print(f"samples {total}; camera pass {camera} ({pct(camera)}); light pass {light} ({pct(light)})")
    for line, n in by_line.most_common():
        if 100 * n / total < 0.5:
            break
        split = ", ".join(f"{c} {pct(k)}" for c, k in cats[line].most_common())
        print(f"{pct(n):>7}  line {line}: {text[line - 1].strip()[:70]}  [{split}]")
    if merge_call:
        print(
            f"merge: grid query {merge_query} ({pct(merge_query)}), body {merge_body} "
            f"({pct(merge_body)}); under a wide query {merge_wide} ({pct(merge_wide)})"
        )


if __name__ == "__main__":
    main()
