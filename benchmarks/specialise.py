"""Cold build of the render program for the scene's own plugin set against the full program, interleaved.

    python benchmarks/specialise.py [--scene XML] [--rounds 3] [--json FILE]

Each round builds both programs (full first, then specialised; the order alternates between rounds) in a new
process with an empty PoCL cache, as `clrender bench` times a cold build (program build + the first launch, which
compiles the work-group function). Reported: medians, the size of the PoCL binary render_pass.so, and the machine
code of the largest functions and the calls to a few builtins (objdump, when installed). Default scene: the
Cornell twin of benchmarks/vs_mitsuba.py. Render speed: benchmarks/ab_pass.py spec: full:D.CLR_USE_ALL_PLUGINS=1.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

BUILTINS = ("_cl_floor", "_cl_clamp", "_cl_fmod")


def _child(job: dict) -> dict:
    """In the new process: build the program and launch it once (nothing runs: pixel_count 0)."""
    from clrender.bench.measure import _timed_build
    from clrender.device.context import get_context

    ctx, queue = get_context(None)
    return _timed_build(ctx, queue, job["defines"], False, job["global_size"], job["local_size"])


def cold(defines: dict, global_size: int, local_size: int) -> dict:
    cache = tempfile.mkdtemp(prefix="clrender-spec-")
    env = dict(os.environ, POCL_CACHE_DIR=cache, PYOPENCL_NO_CACHE="1")
    job = json.dumps({"defines": defines, "global_size": global_size, "local_size": local_size})
    code = ("import json, sys; sys.path.insert(0, %r); from specialise import _child; "
            "print('RESULT ' + json.dumps(_child(json.loads(sys.argv[1]))))" % str(ROOT / "benchmarks"))
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code, job], env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    try:
        line = next(x for x in proc.stdout.splitlines() if x.startswith("RESULT "))
        res = json.loads(line[7:])
        res["process"] = wall
        so = sorted(Path(cache).rglob("render_pass.so"))
        res["so_bytes"] = so[0].stat().st_size if so else None
        if so and shutil.which("objdump"):
            res.update(_code_stats(so[0]))
    finally:
        shutil.rmtree(cache, ignore_errors=True)
    if proc.returncode:
        raise SystemExit(proc.stderr[-2000:])
    return res


def _code_stats(so: Path) -> dict:
    """Sizes of the largest functions (nm) and calls to a few builtins (objdump -d)."""
    nm = subprocess.run(["nm", "--size-sort", "-S", "-C", str(so)], capture_output=True, text=True).stdout
    sizes = []
    for line in nm.splitlines():
        parts = line.split()
        if len(parts) >= 4 and parts[2] in "tT":
            sizes.append((int(parts[1], 16), parts[3]))
    sizes.sort(reverse=True)
    dis = subprocess.run(["objdump", "-d", str(so)], capture_output=True, text=True).stdout
    calls = {b: len(re.findall(rf"call.*<(_Z\d+)?{b}\w*>", dis)) for b in BUILTINS}   # PoCL's names are mangled
    calls["all"] = len(re.findall(r"\scall", dis))
    return {"largest_functions": sizes[:6], "builtin_calls": calls}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--json")
    args = ap.parse_args(argv)

    import clrender
    from clrender.pack import pack_scene
    from clrender.renderer import LOCAL_SIZE, MAX_LAUNCH_PIXELS, render_defines

    from vs_mitsuba import scene_or_cornell_twin

    tmp = tempfile.TemporaryDirectory()
    xml = scene_or_cornell_twin(args.scene, Path(tmp.name))
    scene = clrender.load_scene(xml)
    buffers = pack_scene(scene)
    variants = {"full": render_defines(scene, dataclasses.replace(buffers, plugins=None)),
                "specialised": render_defines(scene, buffers)}
    pixels = min(scene.width * scene.height, MAX_LAUNCH_PIXELS)
    global_size = -(-pixels // LOCAL_SIZE) * LOCAL_SIZE
    runs = {k: [] for k in variants}
    for r in range(args.rounds):
        for name in (list(variants) if r % 2 == 0 else list(variants)[::-1]):
            res = cold(variants[name], global_size, LOCAL_SIZE)
            runs[name].append(res)
            print(f"round {r} {name:12s} build {res['program']:6.2f} s  first launch {res['first_launch']:6.2f} s  "
                  f"process {res['process']:6.2f} s  render_pass.so {res['so_bytes']} B", flush=True)
    out = {"scene": str(xml) if args.scene else "vs_mitsuba cornell twin", "defines": variants, "variants": {}}
    for name, rs in runs.items():
        med = {k: statistics.median(x[k] for x in rs) for k in ("program", "first_launch", "total", "process")}
        out["variants"][name] = {"median": med, "so_bytes": rs[-1]["so_bytes"], "runs": rs}
        print(f"{name:12s} median build {med['program']:.2f} s, first launch {med['first_launch']:.2f} s, "
              f"total {med['total']:.2f} s, process {med['process']:.2f} s; render_pass.so {rs[-1]['so_bytes']} B; "
              f"{rs[-1].get('builtin_calls')}; largest {rs[-1].get('largest_functions', [])[:3]}")
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
