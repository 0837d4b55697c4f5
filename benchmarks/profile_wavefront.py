"""The wavefront driver stage by stage, against the megakernel, on the twins of vs_mitsuba.py.

    python benchmarks/profile_wavefront.py [--spp 16] [--repeat 3] [--res 256] [--only TWIN ...] [--device D]
                                           [--json OUT]

Per twin, in one run: samples/s of the megakernel and of the wavefront (medians of --repeat interleaved renders
after a warm-up, untimed stages), then one more wavefront render with every stage waited for, which gives each
stage's share of the time, and whether PoCL vectorised each stage kernel across work-items: the program is built
in a fresh PoCL cache with POCL_VECTORIZER_REMARKS=1, each stage launched once on its own, and LLVM's loop
vectoriser remark for its work-group loop read ("vectorized loop (vectorization width: 16 ...)" or "loop not
vectorized: <why>"). The device is named in the output; check the load average (these machines are shared).
"""
from __future__ import annotations

import argparse
import ctypes
import datetime as dt
import json
import os
import re
import statistics
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))


def _capture_output(fn):
    """Run fn() with file descriptors 1 and 2 sent to a temporary file (PoCL prints its remarks on stdout); returns
    what was written there."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile() as f:
        os.dup2(f.fileno(), 1)
        os.dup2(f.fileno(), 2)
        try:
            fn()
        finally:
            ctypes.CDLL(None).fflush(None)   # what the C library still holds goes to the file too
            for fd, old in zip((1, 2), saved):
                os.dup2(old, fd)
                os.close(old)
        f.seek(0)
        return f.read().decode(errors="replace")


def vectorised_stages(renderer) -> dict:
    """{stage: LLVM's loop-vectoriser remarks on its work-group loop} (PoCL with POCL_VECTORIZER_REMARKS=1 and a fresh
    cache: PoCL compiles a kernel at its first launch and prints the remarks then, on stdout): each stage launched
    once on its own, over no work."""
    import pyopencl as cl

    ex = renderer.executor
    from clrender.device import layout

    dummy = cl.Buffer(renderer.ctx, cl.mem_flags.READ_WRITE, 64)   # flush's film: it is launched over no pixels
    ex.bind({name: dummy for name, *_ in layout.FILM_ACCUMULATORS})
    out = {}
    for s in ex.STAGES:
        text = _capture_output(lambda: ex.warm(stages=(s,)))
        lv = re.findall(r"(vectorized loop \(vectorization width: \d+[^)]*\)|loop not vectorized: [^<]*)", text)
        out[s] = "; ".join(dict.fromkeys(lv)) or "(no remark: not PoCL, or a warm cache)"
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--only", nargs="*")
    ap.add_argument("--device", help="OpenCL device (index, cpu, gpu, intel or name substring; default PoCL)")
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    # before PoCL starts: remarks, and a cache of our own so every stage is compiled (and remarked) here
    cache = tempfile.mkdtemp(prefix="wf-pocl-cache-")
    os.environ["POCL_CACHE_DIR"] = cache
    os.environ["POCL_VECTORIZER_REMARKS"] = "1"
    import clrender
    from clrender.renderer import Renderer
    from vs_mitsuba import cpu_name, made_twins, scene_xml

    say = lambda m: print(f"profile_wavefront: {m}", file=sys.stderr, flush=True)  # noqa: E731
    load_before = os.getloadavg()
    results = {}
    with tempfile.TemporaryDirectory(prefix="wf-") as tmp:
        for name, d, t in made_twins(tmp, args.only, args.spp, args.res):
            if "xml" in t:
                xml = d / "scene.xml"
                xml.write_text(t["xml"])
            else:
                xml = d / "clrender.xml"
                xml.write_text(scene_xml(t, "nori"))
            scene = clrender.load_scene(xml)
            say(f"{name}: building both programs")
            rs = {}
            remarks = {}
            for drv in ("megakernel", "wavefront"):
                r = None

                def build(drv=drv):
                    nonlocal r
                    r = Renderer(scene, driver=drv, device=args.device)   # builds, and launches a first kernel: PoCL compiles them all
                _capture_output(build)
                if drv == "wavefront":
                    remarks = vectorised_stages(r)
                _capture_output(lambda: r.render(spp=1, seed=1))   # warm-up (its remarks are of no interest)
                rs[drv] = r
            n = rs["megakernel"].n_pixels
            secs = {drv: [] for drv in rs}
            for k in range(args.repeat):
                for drv, r in rs.items():
                    film = r.render(spp=args.spp, seed=100 + k)
                    secs[drv].append(film.stats.seconds)
            wf = rs["wavefront"].executor
            wf.timed = True
            wf.stage_seconds = dict.fromkeys(wf.STAGES, 0.0)
            b0 = wf.bounces
            rs["wavefront"].render(spp=args.spp, seed=99)
            wf.timed = False
            total = sum(wf.stage_seconds.values())
            med = {drv: statistics.median(v) for drv, v in secs.items()}
            results[name] = {
                "pixels": n,
                "samples_per_second": {drv: n * args.spp / m for drv, m in med.items()},
                "wavefront_over_megakernel": med["megakernel"] / med["wavefront"],
                "stages": {s: {"share": wf.stage_seconds[s] / total, "seconds": wf.stage_seconds[s],
                               "vectoriser": remarks.get(s)} for s in wf.STAGES},
                "bounce_launches_per_pass": wf.bounces - b0,
                "all": secs,
            }
            say(f"{name}: wavefront / megakernel {results[name]['wavefront_over_megakernel']:.2f}x")
    dev = rs["megakernel"].device_name
    doc = {"date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "cpu": cpu_name(),
           "cores": os.cpu_count(), "device": dev, "load_average_before": load_before,
           "load_average": os.getloadavg(), "spp": args.spp, "repeat": args.repeat, "res": args.res,
           "results": results}
    print(f"{dev}; load average before {load_before[0]:.2f}, after {os.getloadavg()[0]:.2f}")
    for name, r in results.items():
        sps = r["samples_per_second"]
        print(f"{name}: megakernel {sps['megakernel'] / 1e6:.3f} M samples/s, wavefront {sps['wavefront'] / 1e6:.3f}"
              f" M samples/s ({r['wavefront_over_megakernel']:.2f}x)")
        for s, v in r["stages"].items():
            print(f"    {s:8s} {100 * v['share']:5.1f} %  {v['vectoriser']}")
    if args.json:
        Path(args.json).write_text(json.dumps(doc, indent=1) + "\n")
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
