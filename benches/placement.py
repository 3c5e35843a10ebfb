"""Where a binary's functions sit: for each function whose demangled name ends with one of the
given suffixes, its address modulo 64 and 4096, its size, a hash of its instructions (jump
targets inside it as offsets from its start, other addresses left out, so two builds of the
same code give the same hash wherever they put it) and its loop heads (targets of backward
jumps) as offset from the start / address modulo 64.

    python3 benches/placement.py <binary> Bvh::occluded_avx Bvh::intersect_avx

Needs `nm` and `objdump` (binutils). Used to compare builds of the scale bench whose code
differs elsewhere (docs/measurements.md, "The traversals' placement").
"""

import hashlib
import re
import subprocess
import sys


def run(*args):
    return subprocess.run(args, capture_output=True, text=True, check=True).stdout


def describe(binary, start, size, name):
    out = run("objdump", "-d", "--no-show-raw-insn", f"--start-address={start}",
              f"--stop-address={start + size}", binary)
    heads, norm = set(), []
    for m in re.finditer(r"^\s*([0-9a-f]+):\t(\S+)[ \t]*(.*)$", out, re.M):
        at, op, arg = int(m.group(1), 16), m.group(2), m.group(3)
        j = re.match(r"([0-9a-f]+) <", arg)
        if j:
            to = int(j.group(1), 16)
            arg = f"+{to - start}" if start <= to < start + size else "outside"
            if op.startswith("j") and start <= to <= at:
                heads.add(to)
        arg = re.sub(r"#.*", "", arg)
        arg = re.sub(r"-?0x[0-9a-f]+\(%rip\)", "rip", arg)
        norm.append(f"{at - start} {op} {arg}")
    code = hashlib.sha1("\n".join(norm).encode()).hexdigest()[:10]
    loops = ", ".join(f"{h - start}/{h % 64}" for h in sorted(heads))
    print(f"{name}\n  at {start:#x}: {start % 64} mod 64, {start % 4096:#x} mod 4096; "
          f"{size} bytes; code {code}\n  loop heads (offset/mod 64): {loops}")


def main():
    if len(sys.argv) < 3:
        sys.exit("usage: python3 benches/placement.py BINARY NAME_SUFFIX...")
    binary, suffixes = sys.argv[1], sys.argv[2:]
    for line in run("nm", "-C", "-S", binary).splitlines():
        parts = line.split(" ", 3)
        if len(parts) == 4 and parts[2] in "tT" and any(parts[3].endswith(s) for s in suffixes):
            describe(binary, int(parts[0], 16), int(parts[1], 16), parts[3])


if __name__ == "__main__":
    main()
