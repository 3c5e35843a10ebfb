"""Whether two EXR images have the same channels, bit for bit (the files' bytes may differ from
run to run: the order of their compressed chunks). Prints, for each channel that differs, how
many of its values differ and the largest difference; exits 1 if any does.

    python3 tools/exr_identical.py a.exr b.exr   # a Python with numpy and OpenEXR

Measurement only: nothing in the renderer or its tests imports it.
"""

import sys

import numpy as np
import OpenEXR


def channels(path):
    f = OpenEXR.InputFile(path)
    header = f.header()["channels"]
    return {name: (f.channel(name), header[name].type) for name in sorted(header)}


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: exr_identical.py A.exr B.exr")
    a, b = channels(sys.argv[1]), channels(sys.argv[2])
    if a.keys() != b.keys():
        print(f"different channels: {sorted(a)} against {sorted(b)}")
        sys.exit(1)
    differ = False
    for name in a:
        (x, tx), (y, ty) = a[name], b[name]
        if x == y and str(tx) == str(ty):
            continue
        differ = True
        if len(x) == len(y) and len(x) % 4 == 0 and str(tx) == str(ty) == "FLOAT":
            u, v = np.frombuffer(x, np.float32), np.frombuffer(y, np.float32)
            print(f"{name}: {int((u != v).sum())} of {u.size} values differ, "
                  f"largest by {float(np.nanmax(np.abs(u - v)))}")
        else:
            print(f"{name}: differs ({tx}, {len(x)} bytes against {ty}, {len(y)} bytes)")
    print("identical" if not differ else "different")
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
