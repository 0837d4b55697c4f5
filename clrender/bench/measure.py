"""Measuring one scene on one device: builds (cold and warm), load/pack/upload, timed renders, ray counts,
memory and convergence; and the whole benchmark over scenes x devices (see the package docstring)."""
from __future__ import annotations

import datetime as _dt
import json
import logging
import os
import platform as _platform
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .. import plugins  # noqa: F401  (a composition root: the cold-build child builds the render program)
from ..version import __version__
from ..errors import ClrenderError
from .discovery import default_scenes, load_bench_scene, resolve_devices, scene_hash

log = logging.getLogger("clrender")

SCHEMA = "clrender-bench/1"
RENDER_SOURCE = '#include "render.cl"\n'
SPLAT_SOURCE = '#include "splat.cl"\n'


def _source_and_kernel(defines: dict) -> tuple[str, str]:
    """The program the Renderer builds for these defines (a splatting film's: splat.cl) and its heaviest kernel."""
    return (SPLAT_SOURCE, "render_records") if "CLR_SPLAT" in defines else (RENDER_SOURCE, "render_pass")
RELMSE_EPS = 1e-2


# ------------------------------------------------------------------------------------------------------------
# Builds
# ------------------------------------------------------------------------------------------------------------
def _first_launch(ctx, queue, program, global_size: int, local_size: int, kernel: str = "render_pass") -> float:
    """Seconds for the first enqueue of `kernel` with the renderer's launch shape (pixel_count = 0, so
    nothing runs; PoCL compiles the work-group function for this shape)."""
    import pyopencl as cl

    from ..device.kernelargs import KernelArgs

    k = cl.Kernel(program, kernel)
    args = KernelArgs(k)
    dummy = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, 256)
    counts = ("pixel_offset", "pixel_count", "sample_offset", "spp", "seed", "rec_base")
    args.set(**{n: dummy for n in args.names() if n not in counts})
    args.set(**{n: np.uint32(1 if n == "spp" else 0) for n in args.names() if n in counts})
    t0 = time.perf_counter()
    cl.enqueue_nd_range_kernel(queue, k, (global_size,), (local_size,))
    queue.finish()
    return time.perf_counter() - t0


def _timed_build(ctx, queue, defines, fast_math, global_size, local_size) -> dict:
    from ..device.program import build_program

    t0 = time.perf_counter()
    source, kernel = _source_and_kernel(defines)
    prg = build_program(ctx, source, defines=defines, fast_math=fast_math, use_cache=False)
    t_prog = time.perf_counter() - t0
    t_launch = _first_launch(ctx, queue, prg, global_size, local_size, kernel)
    return {"program": t_prog, "first_launch": t_launch, "total": t_prog + t_launch}


def _cold_build_child() -> None:
    """Entry point of the cold-build subprocess: argv[1] is a JSON job; prints a JSON result."""
    job = json.loads(sys.argv[1])
    from ..device.context import get_context

    ctx, queue = get_context(job["device"])
    res = _timed_build(ctx, queue, job["defines"], job["fast_math"], job["global_size"], job["local_size"])
    print("CLRENDER_BENCH " + json.dumps(res))


def cold_build(device_spec, defines: dict, global_size: int, local_size: int, fast_math: bool = False,
               timeout: float = 900.0) -> dict:
    """Build + first launch in a new process with an empty PoCL cache (see the module docstring)."""
    job = json.dumps({"device": device_spec, "defines": defines, "fast_math": fast_math,
                      "global_size": global_size, "local_size": local_size})
    pkg_parent = str(Path(__file__).resolve().parents[2])
    with tempfile.TemporaryDirectory(prefix="clrender-cold-") as cache:
        env = dict(os.environ)
        env["POCL_CACHE_DIR"] = cache
        env["PYOPENCL_NO_CACHE"] = "1"
        env["PYTHONPATH"] = pkg_parent + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        cmd = [sys.executable, "-c", "from clrender.bench.measure import _cold_build_child; _cold_build_child()", job]
        try:
            proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            raise ClrenderError(f"cold build took longer than {timeout:.0f} s") from None
    for line in proc.stdout.splitlines():
        if line.startswith("CLRENDER_BENCH "):
            return json.loads(line[len("CLRENDER_BENCH "):])
    tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
    raise ClrenderError(f"cold build subprocess failed (exit {proc.returncode}): {tail}")


# ------------------------------------------------------------------------------------------------------------
# Figures
# ------------------------------------------------------------------------------------------------------------
def summarize(values) -> dict:
    """Median, min, max and quartiles of repeated measurements (all values kept)."""
    v = np.asarray([float(x) for x in values], np.float64)
    if v.size == 0:
        return {"median": None, "min": None, "max": None, "q1": None, "q3": None, "values": []}
    q1, med, q3 = np.percentile(v, [25, 50, 75])
    return {"median": float(med), "min": float(v.min()), "max": float(v.max()), "q1": float(q1),
            "q3": float(q3), "values": [float(x) for x in v]}


def relmse(img, ref) -> float:
    """Mean over pixels and channels of (x - r)^2 / (r^2 + 1e-2)."""
    img = np.asarray(img, np.float64)
    ref = np.asarray(ref, np.float64)
    return float(np.mean((img - ref) ** 2 / (ref * ref + RELMSE_EPS)))


def read_exr(path) -> np.ndarray:
    """A reference EXR's RGB as an (H, W, 3) float32 array."""
    from ..film import read_exr as _read

    path = Path(path)
    if not path.is_file():
        raise ClrenderError(f"reference image not found: {path}")
    try:
        return _read(path)[0][..., :3]
    except (KeyError, RuntimeError, OSError) as exc:
        raise ClrenderError(f"{path}: cannot read an RGB image ({exc})") from None


def convergence(renderer, reference: np.ndarray, spp: int, seed: int = 0) -> list[dict]:
    """Progressive renders (1, 1, 2, 4, ... spp; ``spp`` in all) and relMSE of the running image after each."""
    if reference.shape[:2] != (renderer.height, renderer.width):
        raise ClrenderError(f"reference is {reference.shape[1]}x{reference.shape[0]}, the render "
                            f"{renderer.width}x{renderer.height}")
    sum_wl = np.zeros((renderer.height, renderer.width, 3))
    sum_w = np.zeros((renderer.height, renderer.width))
    done, seconds, step, curve = 0, 0.0, 1, []
    while done < spp:
        k = min(step, spp - done)
        film = renderer.render(spp=k, seed=seed, start_sample=done)
        sum_wl += film.sum_wl
        sum_w += film.sum_w
        done += k
        seconds += film.stats.seconds
        w = sum_w[..., None]
        img = np.where(w != 0, sum_wl / np.where(w != 0, w, 1), 0.0)
        curve.append({"spp": done, "seconds": seconds, "relmse": relmse(img, reference)})
        if done > 1:
            step *= 2
    return curve


def _peak_rss_bytes() -> int:
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return int(r if sys.platform == "darwin" else r * 1024)


def git_revision() -> str:
    """``git rev-parse HEAD`` of the checkout this package runs from (or the current folder), else unknown."""
    for where in (Path(__file__).resolve().parents[2], Path.cwd()):
        try:
            out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=where, capture_output=True, text=True,
                                 timeout=10)
        except (OSError, subprocess.SubprocessError):
            continue
        if out.returncode == 0 and re.fullmatch(r"[0-9a-f]{40}", out.stdout.strip()):
            rev = out.stdout.strip()
            dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=where,
                                   capture_output=True, text=True, timeout=10)
            return rev + ("-dirty" if dirty.returncode == 0 and dirty.stdout.strip() else "")
    return "unknown"


def _loadavg():
    """1-minute load average (other processes on the machine make every figure slower), None if unknown."""
    try:
        return round(os.getloadavg()[0], 2)
    except (OSError, AttributeError):
        return None


def _host_info() -> dict:
    cpu = _platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {"hostname": _platform.node(), "os": _platform.platform(), "python": _platform.python_version(),
            "cpu": cpu, "cpu_count": os.cpu_count()}


# ------------------------------------------------------------------------------------------------------------
# The benchmark
# ------------------------------------------------------------------------------------------------------------
def _cl_errors():
    try:
        import pyopencl as cl

        return (ClrenderError, cl.Error, MemoryError)
    except ImportError:  # pragma: no cover
        return (ClrenderError, MemoryError)


class PreparedScene:
    """A scene loaded and packed once for all devices, with its host-side timings."""

    def __init__(self, path, integrator=None, width=None, height=None):
        from ..pack import pack_scene

        self.path = Path(path)
        self.scene, _, self.load_seconds = load_bench_scene(self.path, integrator, width, height)
        self.hash = scene_hash(self.path)
        self.buffers = pack_scene(self.scene)

    def row(self) -> dict:
        sc, st = self.scene, self.buffers.stats
        return {"scene": self.path.stem, "scene_path": str(self.path), "scene_hash": self.hash,
                "integrator": sc.integrator.kernel, "width": sc.width, "height": sc.height,
                "load_seconds": self.load_seconds, "pack_seconds": st["pack_seconds"],
                "bvh_build_seconds": st["bvh_build_seconds"], "triangles": st["triangles"],
                "spheres": st["spheres"], "bvh_nodes": st["bvh_nodes"]}


def bench_one(prepared, dev: dict, *, spp=16, repeat=3, seed=0, reference=None, cold=True, count_rays=True,
              fast_math=False, say=None, driver="auto") -> dict:
    """Measure one scene (a :class:`PreparedScene` or a path) on one device (``dev`` from
    :func:`resolve_devices`) with `driver` (clrender/executors.py); returns a result row. The build timings are of
    the megakernel's program (a wavefront row leaves them out), and rays are counted by the megakernel, which traces
    the very rays of the wavefront (the same samples)."""
    from ..renderer import LOCAL_SIZE, Renderer

    say = say or (lambda msg: None)
    if not isinstance(prepared, PreparedScene):
        prepared = PreparedScene(prepared)
    scene, buffers = prepared.scene, prepared.buffers
    row = {**prepared.row(), "device": dev["name"], "platform": dev["platform"], "device_index": dev["index"],
           "status": "ok", "reason": None, "spp": int(spp), "repeat": int(repeat), "seed": int(seed)}
    if not dev["ok"]:
        row.update(status="skipped", reason=f"cannot build kernels: {dev['reason']}")
        return row
    say(f"{row['scene']} on {dev['name']}: building")
    r = Renderer(scene, device=dev["spec"], buffers=buffers, fast_math=fast_math, driver=driver)
    row["driver"] = r.driver
    row["reconstruction"] = "splat" if r.splat else "sampling"
    row["upload_seconds"] = r.upload_seconds
    defines = r.defines  # exactly the program the renderer runs (integrator, BVH width, ...)
    build = {"first_build_seconds": r.build_seconds}
    if r.driver != "megakernel":
        cold = False   # the timed builds below are of render.cl's program
    if cold:
        c = cold_build(dev["spec"], defines, r.global_size, LOCAL_SIZE, fast_math)
        build.update(cold_program=c["program"], cold_first_launch=c["first_launch"], cold_total=c["total"])
    if r.driver == "megakernel":
        w = _timed_build(r.ctx, r.queue, defines, fast_math, r.global_size, LOCAL_SIZE)
        build.update(warm_program=w["program"], warm_first_launch=w["first_launch"], warm_total=w["total"])
    row["build"] = build
    say(f"{row['scene']} on {dev['name']}: warm-up and {repeat} x {spp} spp")
    r.render(spp=1, seed=seed)  # warm-up: PoCL compiles the launch shape
    n_samples = scene.width * scene.height * int(spp)
    secs, passes = [], []
    for _ in range(int(repeat)):
        film = r.render(spp=spp, seed=seed)
        secs.append(film.stats.seconds)
        passes.append(film.stats.passes)
    row["render_seconds"] = summarize(secs)
    row["samples"] = n_samples
    row["samples_per_second"] = summarize([n_samples / s for s in secs])
    row["pass_seconds"] = summarize([s / spp for s in secs])
    row["launch_passes"] = passes
    row["device_memory_bytes"] = r.device_memory_bytes()
    if count_rays:
        say(f"{row['scene']} on {dev['name']}: counting rays")
        rc = Renderer(scene, device=dev["spec"], buffers=buffers, fast_math=fast_math, count_rays=True,
                      driver="megakernel")
        rc.render(spp=1, seed=seed)
        film = rc.render(spp=spp, seed=seed)
        cam, closest, shadow = film.stats.rays
        total = cam + closest + shadow
        row["rays"] = {"camera": cam, "closest": closest, "shadow": shadow, "total": total,
                       "per_sample": total / n_samples}
        row["rays_per_second"] = summarize([total / s for s in secs])
        row["count_overhead"] = film.stats.seconds / row["render_seconds"]["median"]
        del rc
    else:
        row["rays"] = None
        row["rays_per_second"] = None
    if reference is not None:
        say(f"{row['scene']} on {dev['name']}: convergence against {reference}")
        row["reference"] = str(reference)
        row["convergence"] = convergence(r, read_exr(reference), int(spp), seed)
    else:
        row["convergence"] = None
    row["host_peak_rss_bytes"] = _peak_rss_bytes()
    return row


def _references(scenes, reference):
    if reference is None:
        return [None] * len(scenes)
    if isinstance(reference, dict):
        return [reference.get(str(s)) or reference.get(Path(s).stem) for s in scenes]
    refs = [reference] if isinstance(reference, (str, os.PathLike)) else list(reference)
    if len(refs) != len(scenes):
        raise ClrenderError(f"{len(refs)} reference image(s) for {len(scenes)} scene(s): give one per scene, "
                            "in the same order")
    return refs


def run_benchmark(scenes=None, devices=None, *, integrator: str | None = None, spp: int = 16, repeat: int = 3,
                  width: int | None = None, height: int | None = None, seed: int = 0, reference=None,
                  cold: bool = True, count_rays: bool = True, fast_math: bool = False, scenes_dir=None,
                  progress=None, driver: str = "auto") -> dict:
    """Benchmark ``scenes`` (default: the default set) on ``devices`` (None = default device, "all", or specs).

    ``reference``: one EXR per scene (a path for a single scene, a list, or a {scene: path} dict) for the
    convergence curves. ``cold=False`` skips the cold-build subprocess. ``progress``: a callable taking a
    message. ``driver``: the renderers' (clrender/executors.py). Returns the JSON-ready result dict (see
    :func:`write_json`)."""
    if spp < 1 or repeat < 1:
        raise ClrenderError("spp and repeat must be at least 1")
    scenes = [Path(s) for s in scenes] if scenes else default_scenes(scenes_dir)
    for s in scenes:
        if not s.is_file():
            raise ClrenderError(f"scene file not found: {s}")
    refs = _references(scenes, reference)
    devs = resolve_devices(devices)
    load_start = _loadavg()
    rows = []
    t0 = time.perf_counter()
    for s, ref in zip(scenes, refs):
        if progress:
            progress(f"{s}: loading and packing")
        prepared = PreparedScene(s, integrator, width, height)
        for dev in devs:
            try:
                rows.append(bench_one(prepared, dev, spp=spp, repeat=repeat, seed=seed, reference=ref,
                                      cold=cold, count_rays=count_rays, fast_math=fast_math, say=progress,
                                      driver=driver))
            except _cl_errors() as exc:
                msg = str(exc).strip().splitlines()
                rows.append({**prepared.row(), "device": dev["name"], "platform": dev["platform"],
                             "device_index": dev["index"], "status": "error",
                             "reason": (msg[-1] if msg else type(exc).__name__)[:500]})
                log.warning("bench: %s on %s failed: %s", s, dev["name"], rows[-1]["reason"])
    return {
        "schema": SCHEMA, "clrender_version": __version__, "git_revision": git_revision(),
        "timestamp": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "host": {**_host_info(), "loadavg_start": load_start, "loadavg_end": _loadavg()},
        "settings": {"spp": spp, "repeat": repeat, "seed": seed, "integrator": integrator, "width": width,
                     "height": height, "cold_builds": cold, "count_rays": count_rays, "fast_math": fast_math,
                     "driver": driver},
        "devices": devs, "results": rows, "total_seconds": time.perf_counter() - t0,
    }
