"""Where the time of a whole `clrender render` process goes, outside the render itself.

    python benchmarks/startup.py                                  # the Cornell twin, this tree, 5 runs
    python benchmarks/startup.py --tree before=/tmp/clr-main --tree after=. --runs 5 --cold 1 \
        --json benchmarks/results/startup-DATE.json

Each run starts, per source tree (interleaved, the order rotating from run to run), fresh processes exactly
as the `clrender` console script does (``from clrender.cli import main; sys.exit(main())``; the tree goes
first on PYTHONPATH, so any checkout runs in one virtual environment):
- ``whole``: ``render SCENE --spp N -q``: wall time from spawn to exit, and the render seconds the CLI prints;
- ``first_image``: the same with ``--spp 1`` (time to first image);
- ``phases``: ``--spp 1`` again, under a harness that wraps the functions each phase runs (scene parse, mesh
  loading, device choice and context, packing and BVH, program build, upload, first launch, develop, EXR and
  PNG writes) and logs when each starts and ends, relative to the spawn; intervals that overlap (a build in
  a thread, say) show as such. ``interpreter`` is spawn to the harness's first line, ``imports`` the
  modules the CLI needs (the harness imports them first, to wrap them), ``exit`` the end of the last phase
  to the process's end.
``--cold K`` adds K first-image runs per tree with an empty POCL_CACHE_DIR (what a new user waits for first).
Medians over the runs are reported. PYTHONDONTWRITEBYTECODE is removed from the children's environment (an
installed package has its bytecode compiled), and one untimed run per tree warms the caches first.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LAUNCH = "import sys; from clrender.cli import main; sys.exit(main())"

# (label, module, attribute): the functions whose calls make up each phase, as the CLI path calls them. A
# name missing in a tree is skipped (so older and newer trees can be compared).
WRAPPED = [
    ("output check", "clrender.output", "output_paths"),
    ("scene parse", "clrender.loader", "parse_file"),
    ("mesh check", "clrender.loader", "check_mesh_files"),
    ("instantiate (meshes)", "clrender.loader", "create"),
    ("device + context", "clrender.renderer", "get_context"),
    ("device + context", "clrender.device.context", "get_context"),
    ("film check", "clrender.renderer", "check_film_fits"),
    ("pack", "clrender.renderer", "pack_scene"),
    ("  bvh build", "clrender.pack", "build_bvh"),
    ("  bvh collapse", "clrender.pack", "collapse_bvh4"),
    ("program build", "clrender.renderer", "build_program"),
    ("Renderer()", "clrender.renderer", "Renderer.__init__"),
    ("launches", "clrender.renderer", "wait_for"),
    ("render()", "clrender.renderer", "Renderer.render"),
    ("develop", "clrender.film", "Film.from_accumulators"),
    ("write EXR", "clrender.film", "Film.write_exr"),
    ("write PNG", "clrender.film", "Film.write_png"),
]


def _child_phases() -> None:
    """Harness mode: wrap the phase functions, log each call's interval to $STARTUP_LOG, run the CLI."""
    import functools
    import importlib

    fd = os.open(os.environ["STARTUP_LOG"], os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)

    def log(*items):  # os.write: survives os._exit, which skips Python's buffers
        os.write(fd, (json.dumps(items) + "\n").encode())

    log("interpreter", None, time.time())
    for _, mod, _ in WRAPPED:
        importlib.import_module(mod)
    importlib.import_module("clrender.cli")
    log("imports", None, time.time())

    def wrap(label, owner, name):
        raw = owner.__dict__[name]
        f = raw.__func__ if isinstance(raw, (classmethod, staticmethod)) else raw

        @functools.wraps(f)
        def timed(*a, **k):
            t = time.time()
            try:
                return f(*a, **k)
            finally:
                log(label, t, time.time())

        setattr(owner, name, type(raw)(timed) if isinstance(raw, (classmethod, staticmethod)) else timed)

    for label, mod, attr in WRAPPED:
        owner = sys.modules[mod]
        *path, name = attr.split(".")
        for p in path:
            owner = getattr(owner, p, None)
        if owner is not None and name in getattr(owner, "__dict__", {}):
            wrap(label, owner, name)
    from clrender.cli import main

    sys.argv = ["clrender", *sys.argv[2:]]
    rc = main()
    log("main returned", None, time.time())
    sys.exit(rc)


# The children run in the temporary folder: `python -c` puts its working folder first on sys.path, before
# PYTHONPATH, so started inside a checkout it would import that checkout's clrender whatever the tree.
def _env(tree: Path, cache: str) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = os.pathsep.join([str(tree)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
    env["POCL_CACHE_DIR"] = cache
    return env


def _run(cmd, env) -> tuple[float, float, str]:
    """(wall seconds, CPU seconds (user + system, all threads), stderr) of one child process."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    p = subprocess.run(cmd, env=env, capture_output=True, text=True, cwd=tempfile.gettempdir())
    wall = time.time() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} exited {p.returncode}:\n{p.stderr}")
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), p.stderr


def _render_seconds(stderr: str) -> float:
    m = re.search(r"spp in ([0-9.]+) s", stderr)
    return float(m.group(1)) if m else float("nan")


def whole(tree, scene, spp, out, cache) -> dict:
    """One plain process: wall and CPU seconds, the render seconds it prints, and when its two lines arrived
    (``loaded``: the scene line, printed once the Renderer is ready; ``written``: after both images)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.time()
    p = subprocess.Popen([sys.executable, "-c", LAUNCH, "render", str(scene), "--spp", str(spp), "-q", "-o", str(out)],
                         env=_env(tree, cache), stderr=subprocess.PIPE, text=True, cwd=tempfile.gettempdir())
    marks, lines = {}, []
    for line in p.stderr:
        lines.append(line)
        if "triangles" in line:
            marks.setdefault("loaded", time.time() - t0)
        if "wrote" in line:
            marks.setdefault("written", time.time() - t0)
    p.wait()
    wall = time.time() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    err = "".join(lines)
    if p.returncode != 0:
        raise RuntimeError(f"clrender render exited {p.returncode}:\n{err}")
    return {"wall": wall, "cpu": (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime),
            "render": _render_seconds(err), "loaded": marks.get("loaded", float("nan")),
            "written": marks.get("written", float("nan"))}


def phases(tree, scene, out, cache) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        logf = Path(tmp) / "log.jsonl"
        env = {**_env(tree, cache), "STARTUP_LOG": str(logf)}
        t0 = time.time()
        _run([sys.executable, __file__, "--child-phases", "render", str(scene), "--spp", "1", "-q", "-o", str(out)],
             env)
        t_end = time.time()
        rows = [json.loads(line) for line in logf.read_text().splitlines()]
    out = {}
    t_prev = t0
    for label, start, end in rows:
        if start is None:  # a time stamp: the phase since the previous stamp
            if label != "main returned":
                out[label] = {"seconds": end - t_prev, "start": t_prev - t0, "end": end - t0}
            t_prev = end
            continue
        if label == "launches" and "first launch" not in out:
            label = "first launch"
        p = out.setdefault(label, {"seconds": 0.0, "start": start - t0, "end": end - t0})
        p["seconds"] += end - start
        p["start"], p["end"] = min(p["start"], start - t0), max(p["end"], end - t0)
    last = max(p["end"] for k, p in out.items() if k in ("write EXR", "write PNG"))
    out["exit"] = {"seconds": t_end - t0 - last, "start": last, "end": t_end - t0}
    out["whole"] = {"seconds": t_end - t0, "start": 0.0, "end": t_end - t0}
    return out


def _median(values):
    values = [v for v in values if v == v]
    return statistics.median(values) if values else float("nan")


def twin_scene(folder: Path) -> Path:
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import vs_mitsuba as v

    t = v.twin_cornell(folder, 64)
    (folder / "nori.xml").write_text(v.scene_xml(t, "nori"))
    return folder / "nori.xml"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", help="Nori XML scene (default: the Cornell twin of benchmarks/vs_mitsuba.py)")
    ap.add_argument("--spp", type=int, default=64, help="spp of the whole-process runs (default 64)")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--cold", type=int, default=0, help="cold-cache first-image runs per tree (default 0)")
    ap.add_argument("--no-whole", action="store_true",
                    help="skip the --spp N runs (first image and phases only: more runs in the same time)")
    ap.add_argument("--tree", action="append", metavar="LABEL=PATH",
                    help="a source tree to run (repeatable; default: this checkout)")
    ap.add_argument("--json", metavar="OUT")
    args = ap.parse_args(argv)
    trees = {}
    for item in args.tree or [f"this={ROOT}"]:
        label, _, path = item.partition("=")
        trees[label] = Path(path or label).resolve()
    work = Path(tempfile.mkdtemp(prefix="clrender-startup-"))
    scene = Path(args.scene).resolve() if args.scene else twin_scene(work)
    cache = str(work / "pocl-cache")
    out = work / "out.exr"
    load = [os.getloadavg()[0]]
    for tree in trees.values():  # warm PoCL's cache, the page cache and the bytecode
        whole(tree, scene, 1, out, cache)
    runs = {label: {"whole": [], "first_image": [], "phases": [], "cold_first_image": []} for label in trees}
    labels = list(trees)
    for i in range(args.runs):
        for label in labels[i % len(labels):] + labels[:i % len(labels)]:
            r = runs[label]
            if not args.no_whole:
                r["whole"].append(whole(trees[label], scene, args.spp, out, cache))
            r["first_image"].append(whole(trees[label], scene, 1, out, cache))
            r["phases"].append(phases(trees[label], scene, out, cache))
            said = f"whole {r['whole'][-1]['wall']:.2f} s (render {r['whole'][-1]['render']:.2f} s), " if r["whole"] else ""
            print(f"run {i + 1}/{args.runs} {label}: {said}first image {r['first_image'][-1]['wall']:.2f} s",
                  file=sys.stderr, flush=True)
    for i in range(args.cold):
        for label in labels:
            with tempfile.TemporaryDirectory() as cold:
                runs[label]["cold_first_image"].append(whole(trees[label], scene, 1, out, cold)["wall"])
            print(f"cold {i + 1}/{args.cold} {label}: {runs[label]['cold_first_image'][-1]:.1f} s",
                  file=sys.stderr, flush=True)
    load.append(os.getloadavg()[0])
    summary = {}
    for label, r in runs.items():
        names = list(dict.fromkeys(k for p in r["phases"] for k in p))
        summary[label] = {
            "whole_seconds": _median([w["wall"] for w in r["whole"]]),
            "whole_cpu_seconds": _median([w["cpu"] for w in r["whole"]]),
            "render_seconds": _median([w["render"] for w in r["whole"]]),
            "whole_minus_render_seconds": _median([w["wall"] - w["render"] for w in r["whole"]]),
            "first_image_seconds": _median([w["wall"] for w in r["first_image"]]),
            "first_image_cpu_seconds": _median([w["cpu"] for w in r["first_image"]]),
            # the first image's stages from its own output lines: to the scene line (Renderer ready), from there
            # to both images written, and the exit after that
            "first_image_to_loaded_seconds": _median([w["loaded"] for w in r["first_image"]]),
            "first_image_render_and_write_seconds": _median([w["written"] - w["loaded"] for w in r["first_image"]]),
            "first_image_exit_seconds": _median([w["wall"] - w["written"] for w in r["first_image"]]),
            "cold_first_image_seconds": _median(r["cold_first_image"]),
            "phases": {n: {k: _median([p[n][k] for p in r["phases"] if n in p]) for k in ("seconds", "start", "end")}
                       for n in names},
        }
    result = {"scene": str(scene), "spp": args.spp, "runs": args.runs, "trees": {k: str(v) for k, v in trees.items()},
              "host": {"cpu_count": os.cpu_count(), "machine": platform.machine(), "python": platform.python_version(),
                       "loadavg_start": load[0], "loadavg_end": load[1]},
              "timestamp": time.strftime("%Y-%m-%dT%H:%M:%S"), "summary": summary, "runs_raw": runs}
    print(format_table(result))
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1) + "\n")
        print(f"wrote {args.json}", file=sys.stderr)
    return 0


def format_table(result) -> str:
    s = result["summary"]
    labels = list(s)
    names = list(dict.fromkeys(n for v in s.values() for n in v["phases"]))
    w = max(len(n) for n in names + ["whole process (--spp N)"]) + 2
    head = f"{'ms (median)':<{w}}" + "".join(f"{lab:>22}" for lab in labels)
    lines = [head, "-" * len(head)]
    for n in names:
        cells = []
        for lab in labels:
            p = s[lab]["phases"].get(n)
            cells.append(f"{1000 * p['seconds']:8.0f} @{1000 * p['start']:5.0f}-{1000 * p['end']:5.0f}" if p else
                         f"{'-':>20}")
        lines.append(f"{n:<{w}}" + "".join(f"{c:>22}" for c in cells))
    lines.append("-" * len(head))
    spp = result["spp"]
    for key, name in (("first_image_seconds", "first image (--spp 1)"),
                      ("first_image_cpu_seconds", "  its CPU time"),
                      ("first_image_to_loaded_seconds", "  to the scene line"),
                      ("first_image_render_and_write_seconds", "  then render + write"),
                      ("first_image_exit_seconds", "  then exit"), ("whole_seconds", f"whole (--spp {spp})"),
                      ("render_seconds", f"  render (--spp {spp})"), ("whole_minus_render_seconds", "  whole - render"),
                      ("cold_first_image_seconds", "cold cache, first image")):
        lines.append(f"{name:<{w}}" + "".join(f"{1000 * s[lab][key]:>22.0f}" for lab in labels))
    return "\n".join(lines)


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--child-phases":
        _child_phases()
    else:
        sys.exit(main())
