"""Which kernels does PoCL vectorise across work-items? The question a wavefront design for the CPU stands on.

    python benchmarks/pocl_vectorise.py [--n 4194304] [--repeat 7] [--json OUT]

PoCL runs a work-group as a loop over its work-items and hands that loop to LLVM's loop vectoriser, which can
turn it into AVX2/AVX-512 code that runs 8 or 16 work-items at once, the way Mitsuba's LLVM backend runs its
whole path loop. Our megakernel cannot profit (its traversal and path loops have per-work-item trip counts), but
a wavefront stage (a ray's shading, a camera ray, a BSDF sample) is straight-line code. This times the same
small stage (a hash, a cosine-weighted direction, a tangent frame, a store) written several ways, one
work-item per item, and counts the vector-register instructions (ymm/zmm) in the binary PoCL built. The
result, on PoCL 3.0 here: only code in scalar types over structure-of-arrays buffers, with no call (PoCL's
builtins are calls unless kernels/builtins.h replaces them), is vectorised; one float3 or float4 in the kernel,
even a float4 load or store, and PoCL runs it one work-item at a time.
"""
from __future__ import annotations

import argparse
import datetime as dt
import glob
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HEAD = r"""
inline float u01(uint x) { return (float)(x >> 8) * (1.0f / 16777216.0f); }
#define HASH uint h = i * 0x9E3779B9u ^ seed; h *= 0x85ebca6bu; h ^= h >> 13; \
             float u1 = u01(h), u2 = u01(h * 0x27d4eb2du); \
             float rr = sqrt(u1), x = rr * (u2 - 0.5f), y = rr * (0.5f - u2), z = sqrt(1.0f - u1);
"""
# the stage: a direction (x, y, z) in the frame of the normal n (Duff et al.'s branchless basis), written out
VARIANTS = {
    "scalar SoA in, scalar SoA out": """
        float nx = nin[i], ny = nin[N_ + i], nz = nin[2 * N_ + i]; HASH
        float s = nz >= 0.0f ? 1.0f : -1.0f, a = -1.0f / (s + nz), b = nx * ny * a;
        out[i] = (1.0f + s * nx * nx * a) * x + b * y + nx * z;
        out[N_ + i] = s * b * x + (s + ny * ny * a) * y + ny * z;
        out[2 * N_ + i] = -s * nx * x - ny * y + nz * z;
        out[3 * N_ + i] = u1;""",
    "float3 arithmetic, SoA in and out": """
        float3 n = (float3)(nin[i], nin[N_ + i], nin[2 * N_ + i]); HASH
        float s = n.z >= 0.0f ? 1.0f : -1.0f, a = -1.0f / (s + n.z), b = n.x * n.y * a;
        float3 t = (float3)(1.0f + s * n.x * n.x * a, s * b, -s * n.x), bt = (float3)(b, s + n.y * n.y * a, -n.y);
        float3 d = t * x + bt * y + n * z;
        out[i] = d.x; out[N_ + i] = d.y; out[2 * N_ + i] = d.z; out[3 * N_ + i] = u1;""",
    "scalar arithmetic, float4 in (AoS)": """
        float4 n4 = nin4[i]; float nx = n4.x, ny = n4.y, nz = n4.z; HASH
        float s = nz >= 0.0f ? 1.0f : -1.0f, a = -1.0f / (s + nz), b = nx * ny * a;
        out[i] = (1.0f + s * nx * nx * a) * x + b * y + nx * z;
        out[N_ + i] = s * b * x + (s + ny * ny * a) * y + ny * z;
        out[2 * N_ + i] = -s * nx * x - ny * y + nz * z;
        out[3 * N_ + i] = u1;""",
    "float3 arithmetic, float4 in and out (AoS)": """
        float4 n = nin4[i]; HASH
        float s = n.z >= 0.0f ? 1.0f : -1.0f, a = -1.0f / (s + n.z), b = n.x * n.y * a;
        float3 t = (float3)(1.0f + s * n.x * n.x * a, s * b, -s * n.x), bt = (float3)(b, s + n.y * n.y * a, -n.y);
        float3 d = t * x + bt * y + n.xyz * z;
        out4[i] = (float4)(d, u1);""",
}
CALL_VARIANT = "scalar SoA, sqrt left a PoCL library call"
VARIANTS[CALL_VARIANT] = VARIANTS["scalar SoA in, scalar SoA out"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=1 << 22)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="pocl-vec-") as cache:
        # before PoCL starts: its binaries (in a cache of their own, removed afterwards) are what we inspect
        os.environ["POCL_CACHE_DIR"] = cache
        run(args, cache)


def run(args, cache: str) -> None:
    import pyopencl as cl

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from clrender.device.context import get_context
    from clrender.device.program import build_program
    from vs_mitsuba import cpu_name

    ctx, q = get_context(None)
    n = args.n
    mf = cl.mem_flags
    normals = np.random.default_rng(0).normal(size=(n, 4)).astype(np.float32)
    normals[:, :3] /= np.linalg.norm(normals[:, :3], axis=1, keepdims=True)
    soa = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(normals[:, :3].T))
    aos = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=normals)
    out = cl.Buffer(ctx, mf.READ_WRITE, size=16 * n)
    kernels, vec_lines = {}, {}
    for k, (name, body) in enumerate(VARIANTS.items()):
        src = (f"#define N_ {n}u\n{HEAD}\n__kernel void stage{k}(__global const float* nin, __global const float4* "
               f"nin4, __global float* out, __global float4* out4, uint seed) {{ uint i = get_global_id(0); {body} }}")
        # built as the renderer builds: kernels/builtins.h inlines sqrt (a PoCL library call otherwise, and a
        # call stops the vectoriser); the last variant keeps the call to show that
        defines = {"CLRENDER_BUILTIN_CALLS": 1} if name == CALL_VARIANT else None
        kern = cl.Kernel(build_program(ctx, src, defines=defines, with_types=False), f"stage{k}")
        kern.set_args(soa, aos, out, out, np.uint32(1))
        cl.enqueue_nd_range_kernel(q, kern, (n,), (64,))      # PoCL builds the work-group function here
        q.finish()
        (so,) = glob.glob(f"{cache}/**/stage{k}.so", recursive=True)
        dis = subprocess.run(["objdump", "-d", so], capture_output=True, text=True).stdout.splitlines()
        vec_lines[name] = sum(("ymm" in ln or "zmm" in ln) for ln in dis)
        kernels[name] = kern
    times = {name: [] for name in kernels}
    for _ in range(args.repeat):
        for name, kern in kernels.items():   # interleaved: the machine's state changes affect all alike
            t0 = time.perf_counter()
            cl.enqueue_nd_range_kernel(q, kern, (n,), (64,))
            q.finish()
            times[name].append(time.perf_counter() - t0)
    med = {k: statistics.median(v) for k, v in times.items()}
    dev = ctx.devices[0]
    res = {"date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "cpu": cpu_name(),
           "cores": os.cpu_count(), "device": f"{dev.platform.name.strip()} / {dev.name.strip()}",
           "platform_version": dev.platform.version, "items": n, "repeat": args.repeat,
           "results": {k: {"seconds": med[k], "items_per_second": n / med[k], "ymm_zmm_instructions": vec_lines[k]}
                       for k in kernels}}
    base = med["scalar SoA in, scalar SoA out"]
    print(f"{res['device']} ({res['platform_version']}), {n} items, medians of {args.repeat}")
    for k in kernels:
        print(f"  {k:45s} {med[k] * 1e3:7.2f} ms  {n / med[k] / 1e6:7.1f} M items/s  x{base / med[k]:.2f}  "
              f"{vec_lines[k]:4d} ymm/zmm instructions {'(vectorised)' if vec_lines[k] else '(one work-item at a time)'}")
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1) + "\n")


if __name__ == "__main__":
    main()
