"""Interleaved A/B of render variants in one process: the same scene, the same samples, variants taking turns.

    python benchmarks/ab_pass.py [--scene XML] [--spp 2] [--rounds 15] VARIANT [VARIANT ...]

A VARIANT is a label and settings, ``label:KEY=VALUE,KEY=VALUE``: ``D.NAME=V`` is a -D define of the render
program, ``B.NAME=V`` a build_bvh option (e.g. ``B.traversal_cost=2``), ``W=2`` the BVH width. The first
variant is the baseline. Each round renders --spp samples per pixel with every variant in turn (the same
sample numbers every time); reported: median render seconds, and the median over rounds of each variant's
speed over the baseline's in the same round, which cancels most of a shared machine's drift. Default scene:
the Cornell twin of benchmarks/vs_mitsuba.py.
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))


def _value(v: str):
    try:
        return int(v)
    except ValueError:
        return float(v)


def parse_variant(text: str):
    label, _, rest = text.partition(":")
    defines, bvh, width = {}, {}, None
    for item in filter(None, rest.split(",")):
        k, _, v = item.partition("=")
        if k.startswith("D."):
            defines[k[2:]] = _value(v)
        elif k.startswith("B."):
            bvh[k[2:]] = _value(v)
        elif k == "W":
            width = int(v)
        else:
            raise SystemExit(f"variant {text!r}: {k!r} is not D.NAME, B.NAME or W")
    return label, defines, bvh, width


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("variants", nargs="+")
    ap.add_argument("--scene")
    ap.add_argument("--spp", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--json")
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall",
                    help="cpu: the process's CPU seconds (every thread) per render instead of the render's wall "
                         "time, steadier on a machine that other jobs share (PoCL's idle threads sleep)")
    args = ap.parse_args(argv)

    import clrender
    from clrender.pack import DEFAULT_BVH_WIDTH, pack_scene
    from clrender.renderer import Renderer

    from vs_mitsuba import scene_or_cornell_twin

    tmp = tempfile.TemporaryDirectory()
    xml = scene_or_cornell_twin(args.scene, Path(tmp.name))
    scene = clrender.load_scene(xml)
    runs = []
    for text in args.variants:
        label, defines, bvh, width = parse_variant(text)
        buffers = pack_scene(scene, bvh_width=width or DEFAULT_BVH_WIDTH, bvh_options=bvh)
        r = Renderer(scene, buffers=buffers, defines=defines)
        img = r.render(spp=args.spp, start_sample=1000).image      # build, first launch, warm caches
        runs.append(dict(label=label, renderer=r, seconds=[], mean=float(img.mean()), stats=buffers.stats))
    for _ in range(args.rounds):
        for run in runs:
            c0 = time.process_time()
            wall = run["renderer"].render(spp=args.spp, start_sample=1000).stats.seconds
            run["seconds"].append(wall if args.clock == "wall" else time.process_time() - c0)
    base = runs[0]["seconds"]
    out = {"scene": str(xml) if args.scene else "vs_mitsuba cornell_spheres twin", "spp": args.spp, "clock": args.clock,
           "rounds": args.rounds, "variants": []}
    print(f"{'variant':28s} {'median s':>9s} {'speed vs ' + runs[0]['label']:>18s} {'image mean':>11s} bvh nodes")
    for run in runs:
        ratio = statistics.median(b / s for b, s in zip(base, run["seconds"]))
        med = statistics.median(run["seconds"])
        print(f"{run['label']:28s} {med:9.4f} {ratio:18.3f} {run['mean']:11.5f} {run['stats']['bvh_nodes']}")
        out["variants"].append(dict(label=run["label"], median_seconds=med, speed_ratio=ratio,
                                    seconds=run["seconds"], image_mean=run["mean"],
                                    bvh_nodes=run["stats"]["bvh_nodes"]))
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
