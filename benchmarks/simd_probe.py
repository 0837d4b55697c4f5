"""What shading 8 paths at once in float8 lanes gives on PoCL: benchmarks/simd_probe.cl against the render kernel.

    python benchmarks/simd_probe.py [--spp 8] [--repeat 9] [--variant NAME:DEFINE,...] [--json OUT]

On the diffuse Cornell twin of benchmarks/vs_mitsuba.py (`cornell`: diffuse walls, one quad light, 256x256,
path_mis), interleaved --repeat times: render_pass (the product's kernel, one work-item per pixel) and each
variant of simd_pass (one work-item per 8 pixels, one path per float8 lane, with path regeneration so lanes stay
full: traversal, light selection and the random numbers per lane; the arithmetic of the surface, emission, light
sample, MIS, roulette and BSDF sample in lanes; the hit's table reads per lane or, with PROBE_GATHER8, as index
vectors; PROBE_UNROLL unrolls the per-lane loops). Every variant draws the same random numbers in the same order
as render_pass, so they trace the same paths: their images must agree with render_pass's up to float rounding
(reported), and the speed ratios are what the lanes give. Benchmark only: the probe knows only diffuse meshes
under mesh area lights with constant parameters and uniform light selection, no environment.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from vs_mitsuba import cpu_name, scene_xml, twin_cornell  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spp", type=int, default=8)
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--json")
    ap.add_argument("--variant", action="append", default=[], metavar="NAME:DEFINE,...",
                    help="a build of the probe (repeatable; default: every combination of PROBE_UNROLL and "
                         "PROBE_GATHER8, the probe's switches: lane loops unrolled; gathers as index vectors)")
    args = ap.parse_args(argv)

    import pyopencl as cl

    import clrender
    from clrender.device.kernelargs import KernelArgs
    from clrender.device.program import build_program
    from clrender.renderer import LOCAL_SIZE, Renderer

    tmp = tempfile.TemporaryDirectory()
    d = Path(tmp.name)
    xml = d / "cornell.xml"
    xml.write_text(scene_xml(twin_cornell(d, args.spp, with_spheres=False), "nori"))
    scene = clrender.load_scene(xml)
    r = Renderer(scene)
    r.render(spp=1)
    ctx, queue = r.ctx, r.queue
    n = r.n_pixels
    variants = args.variant or ["lanes:", "unrolled:PROBE_UNROLL", "gathers:PROBE_GATHER8",
                                "gathers+unrolled:PROBE_GATHER8,PROBE_UNROLL"]
    src = (ROOT / "benchmarks" / "simd_probe.cl").read_text()
    mf = cl.mem_flags
    u32 = np.uint32

    def acc():
        return cl.Buffer(ctx, mf.READ_WRITE | mf.COPY_HOST_PTR, hostbuf=np.zeros((n, 4), np.float32))

    acc_pass, acc1 = acc(), acc()
    bad = cl.Buffer(ctx, mf.READ_WRITE | mf.COPY_HOST_PTR, hostbuf=np.zeros(n, np.uint32))
    dummy = cl.Buffer(ctx, mf.READ_WRITE | mf.COPY_HOST_PTR, hostbuf=np.zeros((1, 4), np.uint32))
    g_simd = (-(-(-(-n // 8)) // LOCAL_SIZE) * LOCAL_SIZE,)
    runs, bufs = {}, {}
    for v in variants:
        name, _, defs = v.partition(":")
        prg = build_program(ctx, src, defines={**r.defines, **{x: None for x in filter(None, defs.split(","))}})
        k = cl.Kernel(prg, "simd_pass")
        bufs[name] = acc()
        KernelArgs(k).set_scene(r._scene_bufs).set(cam=r._camera, filter_cdf=r._filter, acc0=bufs[name],
                                                    pixel_count=u32(n), sample_offset=u32(0), spp=u32(args.spp),
                                                    seed=u32(0))
        runs[name] = (k, g_simd)
    k_pass = r.kernel
    r.args.set_scene(r._scene_bufs).set(cam=r._camera, filter_cdf=r._filter, acc0=acc_pass, acc1=acc1, bad=bad,
                                        rays=dummy, pixel_offset=u32(0), pixel_count=u32(n), sample_offset=u32(0),
                                        spp=u32(args.spp), seed=u32(0))
    g_pass = (-(-n // LOCAL_SIZE) * LOCAL_SIZE,)
    runs = {"render_pass": (k_pass, g_pass), **runs}
    bufs["render_pass"] = acc_pass
    for k, g in runs.values():   # warm: PoCL compiles the work-group function at the first launch
        cl.enqueue_nd_range_kernel(queue, k, g, (LOCAL_SIZE,))
        queue.finish()
    img = {}
    for name, buf in bufs.items():
        a = np.zeros((n, 4), np.float32)
        cl.enqueue_copy(queue, a, buf)
        img[name] = a[:, :3] / np.maximum(a[:, 3:], 1e-30)
    times = {k: [] for k in runs}
    load0 = os.getloadavg()
    for _ in range(args.repeat):
        for name, (k, g) in runs.items():
            t0 = time.perf_counter()
            cl.enqueue_nd_range_kernel(queue, k, g, (LOCAL_SIZE,))
            queue.finish()
            times[name].append(time.perf_counter() - t0)
    med = {k: statistics.median(v) for k, v in times.items()}
    ratio = {k: statistics.median(a / b for a, b in zip(times["render_pass"], v)) for k, v in times.items()}
    a = img["render_pass"]
    agree = {}
    for k, b in img.items():
        close = np.all(np.abs(a - b) <= 1e-3 * np.maximum(np.abs(a), np.abs(b)) + 1e-5, axis=-1)
        agree[k] = float(close.mean())
    res = {"date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "cpu": cpu_name(),
           "cores": os.cpu_count(), "device": r.device_name, "load_average": [load0, os.getloadavg()],
           "scene": "vs_mitsuba cornell twin (diffuse, 256x256, path_mis)", "spp_per_launch": args.spp,
           "repeat": args.repeat, "seconds_median": med, "seconds_all": times,
           "samples_per_second": {k: n * args.spp / v for k, v in med.items()},
           "variants": variants, "speed_over_render_pass": ratio, "pixels_agreeing_with_render_pass": agree,
           "image_means": {k: [float(x) for x in v.mean(axis=0)] for k, v in img.items()}}
    path = Path(args.json) if args.json else ROOT / "benchmarks" / "results" / f"simd_probe-{dt.date.today()}.json"
    path.write_text(json.dumps(res, indent=1) + "\n")
    for k, v in med.items():
        print(f"{k:18s} {v * 1e3:9.2f} ms  {n * args.spp / v / 1e6:6.3f} M samples/s  x{ratio[k]:.3f}  "
              f"pixels agreeing {agree[k] * 100:.2f} %")
    print(f"-> {path}")


if __name__ == "__main__":
    main()
