"""Time the BVH build (and optionally traversal on PoCL) for a noisy subdivided sphere of N triangles.

    python benchmarks/bvh_build.py 100000 1000000 [--trace] [--repeat 3]
    python benchmarks/bvh_build.py --mesh scenes/largemesh/meshes/blob_1m.ply --trace

Rays for --trace: "incoherent" = random origins inside the sphere's box with random directions; "camera" =
a pinhole grid looking at the sphere. Both do closest hit with tmax = inf.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from clrender.accel.bvh import build_bvh  # noqa: E402
from clrender.accel.primitives import bvh_leaves, pack_leaf_blocks, primitive_bounds  # noqa: E402


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


def trace_bench(v, bvh, n_rays=1 << 20, repeat=3):
    import pyopencl as cl

    from clrender.device.context import get_context
    from clrender.device.program import build_program

    ctx, queue = get_context(None)
    k = cl.Kernel(build_program(ctx, KERNEL, with_types=False, fast_math=True), "trace")
    prims = pack_leaf_blocks(*v, None, bvh.order, *bvh_leaves(bvh))
    mf = cl.mem_flags
    nodes_b = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=bvh.nodes)
    prims_b = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=prims)
    rng = np.random.default_rng(1)
    side = int(np.sqrt(n_rays))
    x, y = np.meshgrid(np.linspace(-1.2, 1.2, side), np.linspace(-1.2, 1.2, side))
    sets = {
        "incoherent": (rng.uniform(-1, 1, (n_rays, 3)), rng.normal(size=(n_rays, 3))),
        "camera": (np.tile([0.0, 0.0, -4.0], (side * side, 1)),
                   np.stack([x.ravel(), y.ravel(), np.full(side * side, 3.0)], 1)),
    }
    for name, (o, d) in sets.items():
        R = len(o)
        org = np.zeros((R, 4), np.float32)
        dr = np.zeros((R, 4), np.float32)
        org[:, :3], dr[:, :3] = o, d
        ob = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=org)
        db = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=dr)
        out = cl.Buffer(ctx, mf.WRITE_ONLY, 4 * R)
        G = -(-R // 64) * 64
        k(queue, (G,), (64,), nodes_b, prims_b, ob, db, np.uint32(R), out).wait()   # warm-up / compile
        dts = []
        for _ in range(repeat):
            t = time.perf_counter()
            k(queue, (G,), (64,), nodes_b, prims_b, ob, db, np.uint32(R), out).wait()
            dts.append(time.perf_counter() - t)
        print(f"  trace {name:10s}: {R / min(dts) / 1e6:6.2f} M rays/s (best of {repeat})")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sizes", nargs="*", type=int, default=[100_000, 1_000_000])
    ap.add_argument("--trace", action="store_true", help="also time closest-hit traversal on the default device")
    ap.add_argument("--mesh", action="append", default=[], help="a PLY mesh to build over (instead of spheres)")
    ap.add_argument("--repeat", type=int, default=3, help="builds (and trace launches) per input; best is shown")
    a = ap.parse_args()
    inputs = [(f"mesh {m}", lambda m=m: load_mesh(m)) for m in a.mesh]
    if not a.mesh:
        inputs = [(f"sphere {n}", lambda n=n: noisy_sphere(n)) for n in a.sizes]
    for label, make in inputs:
        v = make()
        t = time.perf_counter()
        lo, hi = primitive_bounds(*v, None)
        tb = time.perf_counter() - t
        bvh = min((build_bvh(lo, hi) for _ in range(max(1, a.repeat))), key=lambda b: b.build_seconds)
        print(f"{label} (N={len(lo)}): bounds {tb:.3f}s, build {bvh.build_seconds:.3f}s (best of {a.repeat}), "
              f"nodes {bvh.node_count}, depth {bvh.depth}, SAH {bvh.sah_cost:.2f}, leaves {bvh.leaf_count}")
        if a.trace:
            trace_bench(v, bvh, repeat=max(1, a.repeat))


if __name__ == "__main__":
    main()
