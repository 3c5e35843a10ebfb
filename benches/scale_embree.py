"""Embree 4 (pip package `embreex`) on the scale benchmark's triangles and rays.

Called by `cargo bench --bench scale` as `python scale_embree.py <dir> <triangles>`: reads
`<dir>/mesh.bin`, `camera.bin` and `bounce.bin` (written by benches/scale.rs: little-endian u32
counts, then f32 xyz vertices and u32 triangle indices; rays as f32 origin and direction), and
prints one line per figure:

    build_wall <s>            wall time of the scene build (Embree's own threads: all cores)
    build_cpu <s>             process CPU time of the build
    bytes_per_triangle <b>    resident memory the geometry and its BVH added, per triangle
    <set>/<query>/<threads> <rays/s> <rays/s with the loop cost out>

embreex traces from a Cython loop that copies each ray out of numpy arrays; that loop's cost is
measured on a scene of one triangle no ray comes near and taken out in the last column. One
thread: CPU time of this thread. Two threads: two forked processes sharing the built scene, each
tracing half the rays, timed by wall clock (embreex holds the interpreter lock while tracing).
"""

import os
import sys
import time

import numpy as np
from embreex import rtcore_scene as rtcs
from embreex.mesh_construction import TriangleMesh


def rss():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def read_mesh(path):
    data = open(path, "rb").read()
    nv, nt = np.frombuffer(data[:8], "<u4")
    v = np.frombuffer(data[8 : 8 + nv * 12], "<f4").reshape(-1, 3).copy()
    t = np.frombuffer(data[8 + nv * 12 : 8 + nv * 12 + nt * 12], "<u4").reshape(-1, 3)
    return v, t.astype(np.int32)


def read_rays(path):
    data = open(path, "rb").read()
    (n,) = np.frombuffer(data[:4], "<u4")
    r = np.frombuffer(data[4 : 4 + n * 24], "<f4").reshape(-1, 6)
    return np.ascontiguousarray(r[:, :3]), np.ascontiguousarray(r[:, 3:])


def build(v, t):
    scene = rtcs.EmbreeScene()
    TriangleMesh(scene, v, t)
    # The first query commits (builds) the scene.
    scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))
    return scene


def one_thread(scene, o, d, query):
    c0 = time.thread_time()
    scene.run(o, d, query=query)
    return time.thread_time() - c0


def two_processes(scene, o, d, query):
    half = len(o) // 2
    start = time.perf_counter()
    pids = []
    for a, b in ((0, half), (half, len(o))):
        pid = os.fork()
        if pid == 0:
            scene.run(o[a:b], d[a:b], query=query)
            os._exit(0)
        pids.append(pid)
    for pid in pids:
        _, status = os.waitpid(pid, 0)
        if status != 0:
            raise SystemExit("a tracing process failed")
    return time.perf_counter() - start


def main():
    folder = sys.argv[1]
    v, t = read_mesh(os.path.join(folder, "mesh.bin"))
    before = rss()
    c0, w0 = time.process_time(), time.perf_counter()
    scene = build(v, t)
    print("build_wall", time.perf_counter() - w0)
    print("build_cpu", time.process_time() - c0)
    print("bytes_per_triangle", (rss() - before) / len(t))
    far = np.array([[1e4, 1e4, 1e4], [1e4 + 1e-3, 1e4, 1e4], [1e4, 1e4 + 1e-3, 1e4]], np.float32)
    empty = build(far, np.array([[0, 1, 2]], np.int32))
    for name in ("camera", "bounce"):
        o, d = read_rays(os.path.join(folder, name + ".bin"))
        n = len(o)
        for q, query in (("closest", "INTERSECT"), ("any", "OCCLUDED")):
            loop = min(one_thread(empty, o, d, query) for _ in range(2))
            cpu = one_thread(scene, o, d, query)
            print(f"{name}/{q}/1", n / cpu, n / max(cpu - loop, 1e-9))
            wall = two_processes(scene, o, d, query)
            print(f"{name}/{q}/2", n / wall, n / max(wall - loop / 2, 1e-9))
    sys.stdout.flush()


if __name__ == "__main__":
    main()
