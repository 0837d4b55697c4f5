"""Interleaved A/B of two source trees (e.g. main and a branch) on one scene: renders taking turns.

    git archive main | tar -x -C /tmp/base        # the other tree: any checkout of clrender
    python benchmarks/ab_trees.py /tmp/base . --scene XML [--spp 8] [--rounds 25] [--json OUT]

For changes that ab_pass.py cannot express as a -D define or a build option (different tables, different host
code). Each tree gets one worker process (its own clrender package and kernels, its own PoCL cache) that loads,
packs and renders the scene once (build, first launch, warm caches) and then renders --spp samples per pixel
(the same sample numbers every time) whenever told to; the workers take turns, the order alternating every
round. Reported: median render seconds and process CPU seconds of each tree, and the medians over rounds of
the first tree's time over the second's (> 1: the second is faster), which cancel most of a shared machine's
drift; also each tree's device bytes and a hash of its first image. Default scene: the Cornell twin of
benchmarks/vs_mitsuba.py.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def worker(root: str, xml: str, spp: int) -> None:
    import resource

    sys.path.insert(0, root)
    import numpy as np

    import clrender
    import clrender.device.program as program

    if not clrender.__file__.startswith(str(Path(root).resolve())):
        raise SystemExit(f"clrender was imported from {clrender.__file__}, not from {root}")
    program.kernels_dir = lambda: Path(root) / "kernels"     # an installed clrender would point elsewhere
    from clrender.pack import pack_scene
    from clrender.renderer import Renderer

    scene = clrender.load_scene(xml)
    buffers = pack_scene(scene)
    r = Renderer(scene, buffers=buffers)
    img = np.ascontiguousarray(r.render(spp=spp, start_sample=1000).image)
    print(json.dumps({"image_sha1": hashlib.sha1(img.tobytes()).hexdigest()[:12], "image_mean": float(img.mean()),
                      "device_bytes": buffers.stats["device_bytes"], "triangles": buffers.stats["triangles"]}),
          flush=True)

    def cpu():
        u = resource.getrusage(resource.RUSAGE_SELF)      # every thread of the process (PoCL's too)
        return u.ru_utime + u.ru_stime

    for _ in sys.stdin:
        c = cpu()
        seconds = r.render(spp=spp, start_sample=1000).stats.seconds
        print(seconds, cpu() - c, flush=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("trees", nargs=2, help="the two source trees (A, B)")
    ap.add_argument("--scene")
    ap.add_argument("--spp", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=25)
    ap.add_argument("--json")
    if argv is None and len(sys.argv) > 1 and sys.argv[1] == "--worker":
        return worker(sys.argv[2], sys.argv[3], int(sys.argv[4]))
    args = ap.parse_args(argv)
    tmp = tempfile.TemporaryDirectory()
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from vs_mitsuba import scene_or_cornell_twin

    xml = str(scene_or_cornell_twin(args.scene, Path(tmp.name)).resolve())
    names = ["A", "B"]
    procs, info = {}, {}
    for name, root in zip(names, args.trees):
        env = dict(os.environ, POCL_CACHE_DIR=str(Path(tmp.name) / f"pocl-{name}"))
        procs[name] = subprocess.Popen([sys.executable, __file__, "--worker", str(Path(root).resolve()), xml,
                                        str(args.spp)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
                                       env=env)
        line = procs[name].stdout.readline()
        if not line:
            raise SystemExit(f"the worker of tree {root} failed")
        info[name] = json.loads(line)
    secs = {n: [] for n in names}
    cpus = {n: [] for n in names}
    for k in range(args.rounds):
        for n in names if k % 2 == 0 else names[::-1]:
            procs[n].stdin.write("go\n")
            procs[n].stdin.flush()
            w, c = procs[n].stdout.readline().split()
            secs[n].append(float(w))
            cpus[n].append(float(c))
    for p in procs.values():
        p.stdin.close()
        p.wait()
    out = {"scene": args.scene or "vs_mitsuba cornell_spheres twin", "spp": args.spp, "rounds": args.rounds,
           "trees": dict(zip(names, args.trees)), "first_image": info,
           "median_seconds": {n: statistics.median(v) for n, v in secs.items()},
           "median_cpu_seconds": {n: statistics.median(v) for n, v in cpus.items()},
           "speed_B_over_A": statistics.median(a / b for a, b in zip(secs["A"], secs["B"])),
           "cpu_speed_B_over_A": statistics.median(a / b for a, b in zip(cpus["A"], cpus["B"])),
           "seconds": secs, "cpu_seconds": cpus}
    for n in names:
        print(f"{n} {args.trees[names.index(n)]}: median {out['median_seconds'][n]:.4f} s "
              f"(CPU {out['median_cpu_seconds'][n]:.4f} s), {info[n]['device_bytes']:,} device bytes, "
              f"image {info[n]['image_sha1']} mean {info[n]['image_mean']:.6f}")
    print(f"B over A (median over rounds of A's time / B's): {out['speed_B_over_A']:.3f} wall, "
          f"{out['cpu_speed_B_over_A']:.3f} CPU")
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
