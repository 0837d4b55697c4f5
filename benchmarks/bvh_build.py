"""Time the BVH build (and optionally traversal on PoCL) for a noisy subdivided sphere of N triangles.

    python benchmarks/bvh_build.py 100000 1000000 [--trace] [--repeat 3]
    python benchmarks/bvh_build.py --mesh scenes/largemesh/meshes/blob_1m.ply --trace --embree \
        --methods host,device --json benchmarks/results/bvh_build-DATE.json

Each build method ("host": every level in numpy; "device": top levels in numpy, subtrees in OpenCL; see
build_bvh) is timed ``--repeat`` times, interleaved with the others, and the median is reported. ``--embree``
also times Embree's build of the same triangles (``pip install embreex``: benchmark-only, never a
dependency): scene creation + commit, on all the cores it wants (TBB).

Rays for --trace: "incoherent" = random origins inside the sphere's box with random directions; "camera" =
a pinhole grid looking at the sphere. Both do closest hit with tmax = inf.
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import clrender.plugins  # noqa: E402,F401  (its kernels are built with the row types)
from clrender.accel.bvh import build_bvh  # noqa: E402
from clrender.accel.primitives import bvh_leaves, pack_leaf_blocks, primitive_bounds  # noqa: E402
from vs_mitsuba import cpu_name  # noqa: E402


def noisy_sphere(n, seed=0):
    """About n small triangles scattered over a bumpy unit sphere (a stand-in for a displaced mesh)."""
    rng = np.random.default_rng(seed)
    c = rng.normal(size=(n, 3))
    c /= np.linalg.norm(c, axis=1, keepdims=True)
    c *= 1 + 0.05 * np.sin(12 * c[:, :1]) * np.cos(9 * c[:, 1:2])
    s = 2.5 / np.sqrt(n)
    return tuple(c + rng.normal(size=(n, 3)) * s for _ in range(3))


def load_mesh(path):
    from clrender.shapes.plyfile import load_ply

    m = load_ply(path)
    t = np.asarray(m.positions)[np.asarray(m.faces)]
    return t[:, 0], t[:, 1], t[:, 2]


KERNEL = r"""
#include "bvh.h"
__kernel void trace(__global const float4* nodes, __global const float4* prims, __global const float4* org,
                    __global const float4* dir, uint n, __global float* out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    float4 o = org[i], d = dir[i];
    Hit h;
    out[i] = bvh_closest_hit(nodes, prims, o.xyz, d.xyz, 0.0f, INFINITY, &h) ? h.t : -1.0f;
}
"""


def embree_build_seconds(v):
    """Embree's BVH build of the triangles v (scene + mesh creation and commit), or None without embreex."""
    try:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
    except ImportError:
        print("  (embreex is not installed: pip install embreex)")
        return None
    tris = np.ascontiguousarray(np.stack(v, axis=1), np.float32)       # (N, 3, 3)
    one = np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32)
    t, c = time.perf_counter(), time.process_time()
    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, tris)
    scene.run(*one)                                                     # the first query commits (builds)
    return time.perf_counter() - t, time.process_time() - c


def trace_bench(v, trees, n_rays=1 << 18, repeat=3):
    """Closest-hit M rays/s of each tree in ``trees`` (name -> BVH) with the renderer's 2-wide (bvh.h) and
    4-wide (bvh4.h, the default) traversal; launches interleaved across the trees, median of ``repeat``."""
    import pyopencl as cl

    from clrender.accel.bvh4 import collapse_bvh4
    from clrender.device.context import get_context
    from clrender.device.program import build_program

    ctx, queue = get_context(None)
    mf = cl.mem_flags
    buf = lambda a: cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(a))  # noqa
    kernels = {w: cl.Kernel(build_program(ctx, KERNEL if w == 2 else KERNEL.replace('"bvh.h"', '"bvh4.h"'),
                                          fast_math=True),
                            "trace") for w in (2, 4)}
    bufs = {}
    for name, bvh in trees.items():
        prims = buf(pack_leaf_blocks(*v, None, bvh.order, *bvh_leaves(bvh)))
        bufs[name, 2] = (buf(bvh.nodes), prims)
        bufs[name, 4] = (buf(collapse_bvh4(bvh).nodes), prims)
    rng = np.random.default_rng(1)
    side = int(np.sqrt(n_rays))
    x, y = np.meshgrid(np.linspace(-1.2, 1.2, side), np.linspace(-1.2, 1.2, side))
    sets = {
        "incoherent": (rng.uniform(-1, 1, (n_rays, 3)), rng.normal(size=(n_rays, 3))),
        "camera": (np.tile([0.0, 0.0, -4.0], (side * side, 1)),
                   np.stack([x.ravel(), y.ravel(), np.full(side * side, 3.0)], 1)),
    }
    res = {name: {} for name in trees}
    for set_name, (o, d) in sets.items():
        R = len(o)
        org = np.zeros((R, 4), np.float32)
        dr = np.zeros((R, 4), np.float32)
        org[:, :3], dr[:, :3] = o, d
        ob, db = buf(org), buf(dr)
        out = cl.Buffer(ctx, mf.WRITE_ONLY, 4 * R)
        G = -(-R // 64) * 64
        for w, k in kernels.items():
            dts = {name: [] for name in trees}
            for name in trees:                                      # warm-up / compile
                k(queue, (G,), (64,), *bufs[name, w], ob, db, np.uint32(R), out).wait()
            for _ in range(repeat):
                for name in trees:
                    t = time.perf_counter()
                    k(queue, (G,), (64,), *bufs[name, w], ob, db, np.uint32(R), out).wait()
                    dts[name].append(time.perf_counter() - t)
            for name in trees:
                key = f"{set_name}_bvh{w}"
                res[name][key] = R / statistics.median(dts[name]) / 1e6
                print(f"  trace {key:16s} [{name}]: {res[name][key]:6.2f} M rays/s (median of {repeat})")
    return res


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sizes", nargs="*", type=int, default=[100_000, 1_000_000])
    ap.add_argument("--trace", action="store_true", help="also time closest-hit traversal on the default device")
    ap.add_argument("--mesh", action="append", default=[], help="a PLY mesh to build over (instead of spheres)")
    ap.add_argument("--repeat", type=int, default=3, help="builds (and trace launches) per input; median shown")
    ap.add_argument("--methods", default="auto", help="comma-separated build_bvh methods: auto, host, device")
    ap.add_argument("--embree", action="store_true", help="also time Embree's build (needs embreex)")
    ap.add_argument("--json", help="write the results here")
    a = ap.parse_args()
    methods = a.methods.split(",")
    inputs = [(f"mesh {m}", lambda m=m: load_mesh(m)) for m in a.mesh]
    if not a.mesh:
        inputs = [(f"sphere {n}", lambda n=n: noisy_sphere(n)) for n in a.sizes]
    rows = []
    for label, make in inputs:
        v = make()
        t = time.perf_counter()
        lo, hi = primitive_bounds(*v, None)
        tb = time.perf_counter() - t
        for m in methods:
            build_bvh(lo[:20000], hi[:20000], method=m)                 # warm-up: compiles the kernel
        times = {m: [] for m in methods}
        cpu = {m: [] for m in methods}
        times["embree"], cpu["embree"] = [], []
        trees = {}
        for _ in range(max(1, a.repeat)):                              # interleaved: noise hits all alike
            for m in methods:
                c = time.process_time()
                trees[m] = build_bvh(lo, hi, method=m)
                cpu[m].append(time.process_time() - c)                 # all threads (PoCL's too)
                times[m].append(trees[m].build_seconds)
            if a.embree:
                e = embree_build_seconds(v)
                if e is not None:
                    times["embree"].append(e[0])
                    cpu["embree"].append(e[1])
        row = {"input": label, "n_prims": len(lo), "bounds_seconds": tb, "builds": {}}
        if times["embree"]:
            row["embree_seconds"] = times["embree"]
            row["embree_median"] = statistics.median(times["embree"])
            row["embree_cpu_seconds"] = cpu["embree"]
            print(f"{label}: Embree build {row['embree_median']:.3f}s (median of {len(times['embree'])}), "
                  f"CPU {statistics.median(cpu['embree']):.3f}s")
        for m in methods:
            bvh = trees[m]
            med = statistics.median(times[m])
            r = {"seconds": times[m], "median": med, "cpu_seconds": cpu[m], "sah_cost": bvh.sah_cost,
                 "node_count": bvh.node_count, "depth": bvh.depth, "leaves": bvh.leaf_count}
            ratio = f", {med / row['embree_median']:.2f}x Embree" if times["embree"] else ""
            print(f"{label} (N={len(lo)}) [{m}]: bounds {tb:.3f}s, build {med:.3f}s (median of {a.repeat}"
                  f"{ratio}), CPU {statistics.median(cpu[m]):.3f}s, nodes {bvh.node_count}, depth {bvh.depth}, SAH {bvh.sah_cost:.3f}, "
                  f"leaves {bvh.leaf_count}")
            row["builds"][m] = r
        if a.trace:
            for m, t in trace_bench(v, trees, repeat=max(1, a.repeat)).items():
                row["builds"][m]["trace_mrays"] = t
        rows.append(row)
    if a.json:
        import os

        out = {"cpu": cpu_name(), "command": " ".join(sys.argv), "cpu_count": os.cpu_count(), "loadavg": os.getloadavg(),
               "numpy": np.__version__, "timestamp": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "rows": rows}
        Path(a.json).parent.mkdir(parents=True, exist_ok=True)
        Path(a.json).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
