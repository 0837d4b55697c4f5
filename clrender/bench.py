"""Cross-device benchmark: ``clrender bench`` and the Python API behind it.

    from clrender.bench import run_benchmark, format_table, write_json
    result = run_benchmark(["scenes/cornell/cornell_path_mis.xml"], devices="all", spp=16, repeat=3)
    print(format_table(result)); write_json(result, "bench.json")

For every scene x device this measures, each on its own:

- **build, cold**: building the render program and compiling its one launch shape in a fresh process whose
  ``POCL_CACHE_DIR`` is a new empty folder (PoCL reads its environment once, at initialisation, so only a new
  process gets a cold cache). ``program`` is clBuildProgram; ``first_launch`` is the first enqueue of the
  kernel, where PoCL compiles the work-group function for the launch shape.
- **build, warm**: the same two steps in this process with the disk cache filled, bypassing clrender's
  in-memory program cache (``build_program(..., use_cache=False)``).
- **load** (XML parse + plugin construction, which reads the meshes), **pack** (all tables, including the
  BVH) and **BVH build** (``SceneBuffers.stats``), and the upload of the tables to the device.
- **render**: after one warm-up render (1 spp), ``repeat`` renders of ``spp`` samples per pixel with the same
  seed, so every repetition traces exactly the same rays. From each: samples/s (pixels x spp / seconds),
  time per pass (seconds for one sample in every pixel) and rays/s. We report the median and the spread
  (min, max, quartiles) and keep every repetition's value.
- **rays**: one more render of the same samples with a program built with ``-DCLRENDER_COUNT_RAYS``; the
  kernels count camera rays, other closest-hit (extension) rays and shadow (any-hit) rays. The counts are
  exact for the timed renders (same seed, same samples); rays/s = rays / timed seconds. The timed renders use
  the normal program, which contains no counting code; the counting render's own time is kept as
  ``count_overhead`` (its time over the median).
- **memory**: device bytes (uploaded tables + camera + filter table + per-pixel accumulators) and the host's
  peak resident set size so far (process-wide, so it only grows from row to row).
- **convergence** (with a reference EXR): progressive renders of 1, 1, 2, 4, ... spp (``spp`` in total); after
  each, relMSE = mean over pixels and channels of (x - r)^2 / (r^2 + 1e-2) against render time.
"""
from __future__ import annotations

import datetime as _dt
import hashlib
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

from .version import __version__
from . import plugins  # noqa: F401  (a composition root: the cold-build child builds the render program)
from .errors import ClrenderError

log = logging.getLogger("clrender")

SCHEMA = "clrender-bench/1"
#: the default benchmark set, relative to the repository's scenes/ folder
DEFAULT_SCENES = ("cornell/cornell_path_mis.xml", "mis/mis_path_mis.xml", "largemesh/largemesh_path_mis.xml")
RENDER_SOURCE = '#include "render.cl"\n'
RELMSE_EPS = 1e-2


# ------------------------------------------------------------------------------------------------------------
# Scenes
# ------------------------------------------------------------------------------------------------------------
def find_scenes_dir(scenes_dir=None) -> Path:
    """The repository's scenes/ folder: ``scenes_dir`` if given, else ./scenes or a parent's scenes/, else the
    source checkout beside this package (the installed package does not ship scenes)."""
    if scenes_dir is not None:
        p = Path(scenes_dir)
        if not (p / DEFAULT_SCENES[0]).is_file():
            raise ClrenderError(f"--scenes-dir {p}: no {DEFAULT_SCENES[0]} there")
        return p
    here = Path.cwd().resolve()
    candidates = [d / "scenes" for d in (here, *here.parents)]
    candidates.append(Path(__file__).resolve().parents[1] / "scenes")
    for c in candidates:
        if (c / DEFAULT_SCENES[0]).is_file():
            return c
    raise ClrenderError("cannot find the default benchmark scenes (scenes/" + DEFAULT_SCENES[0] + "): run from "
                        "a clrender checkout (scenes/ in the current folder or a parent), pass --scenes-dir, "
                        "or name scene files")


def default_scenes(scenes_dir=None) -> list[Path]:
    d = find_scenes_dir(scenes_dir)
    _generate_large_meshes(d)
    return [d / s for s in DEFAULT_SCENES if (d / s).is_file()]


def _generate_large_meshes(d: Path) -> None:
    """The large-mesh scene's PLYs are generated on demand by the checkout's scenes/build.py (not kept in git)."""
    import subprocess
    import sys

    build = d / "build.py"
    if build.is_file() and not (d / "largemesh" / "meshes" / "blob_1m.ply").is_file():
        r = subprocess.run([sys.executable, str(build), "--large-meshes", "--out", str(d)], capture_output=True,
                           text=True)
        if r.returncode != 0:
            raise ClrenderError(f"generating the large benchmark meshes with {build} failed:\n{r.stderr[-2000:]}")


def _referenced_files(spec) -> list[tuple[str, Path]]:
    out = []
    for s in spec.walk():
        for name in s.props:
            if s.props.tag(name) == "string" and name == "filename":
                raw = s.props.raw(name) or name
                p = Path(s.props._entry(name).value)
                out.append((raw, p))
    return out


def scene_hash(path, spec=None) -> str:
    """sha256 over the XML file and every file it references (by the name written in the XML, then bytes)."""
    from .scene.xmlparser import parse_file

    path = Path(path)
    if spec is None:
        spec = parse_file(str(path))
    h = hashlib.sha256()
    h.update(path.read_bytes())
    for raw, p in _referenced_files(spec):
        h.update(b"\0" + raw.encode() + b"\0")
        try:
            with open(p, "rb") as f:
                for chunk in iter(lambda: f.read(1 << 20), b""):
                    h.update(chunk)
        except OSError:
            h.update(b"<missing>")
    return h.hexdigest()


def load_bench_scene(path, integrator: str | None = None, width: int | None = None, height: int | None = None):
    """Load a scene as `clrender render` does (clrender.load_scene), optionally with another integrator (made by
    the registry, as if the file named it) or resolution. Returns (scene, spec, seconds)."""
    from .loader import load_scene
    from .scene.registry import instantiate

    t0 = time.perf_counter()
    scene = load_scene(path)
    if integrator and scene.integrator.spec.type != integrator:
        # av is the one integrator with a required property: the length scale of the scene
        props = {"length": ("float", 1.0)} if integrator == "av" else {}
        scene.integrator = instantiate("integrator", integrator, props, scene.integrator.spec.location)
    if width:
        scene.camera.width = int(width)
    if height:
        scene.camera.height = int(height)
    return scene, scene.spec, time.perf_counter() - t0


# ------------------------------------------------------------------------------------------------------------
# Devices
# ------------------------------------------------------------------------------------------------------------
def device_info(platform, device) -> dict:
    return {
        "platform": platform.name.strip(), "platform_version": platform.version.strip(),
        "name": device.name.strip(), "vendor": device.vendor.strip(),
        "opencl_version": device.version.strip(), "opencl_c_version": device.opencl_c_version.strip(),
        "driver_version": device.driver_version.strip(), "compute_units": int(device.max_compute_units),
        "global_mem_bytes": int(device.global_mem_size),
    }


def resolve_devices(devices=None) -> list[dict]:
    """``None`` = the default device; ``"all"`` = every device; else a list (or comma-separated string) of
    device SPECs as ``--device`` takes. Each entry says whether the device can build kernels."""
    from .device.context import build_check, choose_device, is_simulator, list_devices

    listed = list_devices()

    def index_of(p, d):
        for i, (p2, d2) in enumerate(listed):
            if d2.int_ptr == d.int_ptr:
                return i
        return None

    if devices is None or devices == "" or devices == "default":
        pairs = [(None, choose_device(None))]
    elif isinstance(devices, str) and devices.strip().lower() == "all":
        pairs = [(str(i), pd) for i, pd in enumerate(listed)]
    else:
        specs = [s.strip() for s in devices.split(",")] if isinstance(devices, str) else [str(s) for s in devices]
        pairs = [(s, choose_device(s)) for s in specs if s]
    every = isinstance(devices, str) and devices.strip().lower() == "all"
    out, seen = [], set()
    for spec, (p, d) in pairs:
        i = index_of(p, d)
        if i in seen:
            continue
        seen.add(i)
        if every and is_simulator(d):
            # thousands of times slower: the default set would run for hours (the test extra installs Oclgrind)
            why = "a simulator, not benchmarked with --devices all (name it to benchmark it)"
        else:
            why = build_check(p, d)
        out.append({"index": i, "spec": str(i) if i is not None else spec, "ok": why is None, "reason": why,
                    **device_info(p, d)})
    return out


# ------------------------------------------------------------------------------------------------------------
# Builds
# ------------------------------------------------------------------------------------------------------------
def _first_launch(ctx, queue, program, global_size: int, local_size: int) -> float:
    """Seconds for the first enqueue of render_pass with the renderer's launch shape (pixel_count = 0, so
    nothing runs; PoCL compiles the work-group function for this shape)."""
    import pyopencl as cl

    from .device.kernelargs import KernelArgs

    k = cl.Kernel(program, "render_pass")
    args = KernelArgs(k)
    dummy = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, 256)
    counts = ("pixel_offset", "pixel_count", "sample_offset", "spp", "seed")
    args.set(**{n: dummy for n in args.names() if n not in counts})
    args.set(pixel_offset=np.uint32(0), pixel_count=np.uint32(0), sample_offset=np.uint32(0), spp=np.uint32(1),
             seed=np.uint32(0))
    t0 = time.perf_counter()
    cl.enqueue_nd_range_kernel(queue, k, (global_size,), (local_size,))
    queue.finish()
    return time.perf_counter() - t0


def _timed_build(ctx, queue, defines, fast_math, global_size, local_size) -> dict:
    from .device.program import build_program

    t0 = time.perf_counter()
    prg = build_program(ctx, RENDER_SOURCE, defines=defines, fast_math=fast_math, use_cache=False)
    t_prog = time.perf_counter() - t0
    t_launch = _first_launch(ctx, queue, prg, global_size, local_size)
    return {"program": t_prog, "first_launch": t_launch, "total": t_prog + t_launch}


def _cold_build_child() -> None:
    """Entry point of the cold-build subprocess: argv[1] is a JSON job; prints a JSON result."""
    job = json.loads(sys.argv[1])
    from .device.context import get_context

    ctx, queue = get_context(job["device"])
    res = _timed_build(ctx, queue, job["defines"], job["fast_math"], job["global_size"], job["local_size"])
    print("CLRENDER_BENCH " + json.dumps(res))


def cold_build(device_spec, defines: dict, global_size: int, local_size: int, fast_math: bool = False,
               timeout: float = 900.0) -> dict:
    """Build + first launch in a new process with an empty PoCL cache (see the module docstring)."""
    job = json.dumps({"device": device_spec, "defines": defines, "fast_math": fast_math,
                      "global_size": global_size, "local_size": local_size})
    pkg_parent = str(Path(__file__).resolve().parents[1])
    with tempfile.TemporaryDirectory(prefix="clrender-cold-") as cache:
        env = dict(os.environ)
        env["POCL_CACHE_DIR"] = cache
        env["PYOPENCL_NO_CACHE"] = "1"
        env["PYTHONPATH"] = pkg_parent + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        cmd = [sys.executable, "-c", "import sys; from clrender.bench import _cold_build_child; _cold_build_child()",
               job]
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
    from .film import read_exr as _read

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
    for where in (Path(__file__).resolve().parents[1], Path.cwd()):
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
        from .pack import pack_scene

        self.path = Path(path)
        self.scene, spec, self.load_seconds = load_bench_scene(self.path, integrator, width, height)
        self.hash = scene_hash(self.path, spec)
        self.buffers = pack_scene(self.scene)

    def row(self) -> dict:
        sc, st = self.scene, self.buffers.stats
        return {"scene": self.path.stem, "scene_path": str(self.path), "scene_hash": self.hash,
                "integrator": sc.integrator.kernel, "width": sc.width, "height": sc.height,
                "load_seconds": self.load_seconds, "pack_seconds": st["pack_seconds"],
                "bvh_build_seconds": st["bvh_build_seconds"], "triangles": st["triangles"],
                "spheres": st["spheres"], "bvh_nodes": st["bvh_nodes"]}


def bench_one(prepared, dev: dict, *, spp=16, repeat=3, seed=0, reference=None, cold=True, count_rays=True,
              fast_math=False, say=None) -> dict:
    """Measure one scene (a :class:`PreparedScene` or a path) on one device (``dev`` from
    :func:`resolve_devices`); returns a result row."""
    from .renderer import LOCAL_SIZE, Renderer

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
    r = Renderer(scene, device=dev["spec"], buffers=buffers, fast_math=fast_math)
    row["upload_seconds"] = r.upload_seconds
    defines = r.defines  # exactly the program the renderer runs (integrator, BVH width, ...)
    build = {"first_build_seconds": r.build_seconds}
    if cold:
        c = cold_build(dev["spec"], defines, r.global_size, LOCAL_SIZE, fast_math)
        build.update(cold_program=c["program"], cold_first_launch=c["first_launch"], cold_total=c["total"])
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
        rc = Renderer(scene, device=dev["spec"], buffers=buffers, fast_math=fast_math, count_rays=True)
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
                  progress=None) -> dict:
    """Benchmark ``scenes`` (default: the default set) on ``devices`` (None = default device, "all", or specs).

    ``reference``: one EXR per scene (a path for a single scene, a list, or a {scene: path} dict) for the
    convergence curves. ``cold=False`` skips the cold-build subprocess. ``progress``: a callable taking a
    message. Returns the JSON-ready result dict (see :func:`write_json`)."""
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
                                      cold=cold, count_rays=count_rays, fast_math=fast_math, say=progress))
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
                     "height": height, "cold_builds": cold, "count_rays": count_rays, "fast_math": fast_math},
        "devices": devs, "results": rows, "total_seconds": time.perf_counter() - t0,
    }


# ------------------------------------------------------------------------------------------------------------
# Output
# ------------------------------------------------------------------------------------------------------------
def write_json(result: dict, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(result, indent=1, sort_keys=False) + "\n")
    os.replace(tmp, path)
    return path


def load_json(path) -> dict:
    try:
        data = json.loads(Path(path).read_text())
    except OSError as exc:
        raise ClrenderError(f"cannot read {path}: {exc.strerror or exc}") from None
    except json.JSONDecodeError as exc:
        raise ClrenderError(f"{path}: not JSON ({exc})") from None
    if not isinstance(data, dict) or data.get("schema", "").split("/")[0] != SCHEMA.split("/")[0]:
        raise ClrenderError(f"{path}: not a clrender bench result (no '{SCHEMA}' schema field)")
    return data


def _fmt_rate(v):
    return "-" if v is None else f"{v / 1e6:.3g} M"


def _med(x):
    return None if not x else x.get("median")


def _fmt_s(v, ms=False):
    if v is None:
        return "-"
    return f"{v * 1e3:.3g} ms" if ms else f"{v:.3g} s"


def _fmt_bytes(v):
    if v is None:
        return "-"
    for unit, f in (("GiB", 2 ** 30), ("MiB", 2 ** 20), ("KiB", 2 ** 10)):
        if v >= f:
            return f"{v / f:.3g} {unit}"
    return f"{v} B"


def _table(headers, rows) -> str:
    widths = [max(len(str(h)), *(len(str(r[i])) for r in rows)) if rows else len(str(h))
              for i, h in enumerate(headers)]
    line = "  ".join(str(h).ljust(w) for h, w in zip(headers, widths))
    out = [line, "  ".join("-" * w for w in widths)]
    for r in rows:
        out.append("  ".join(str(c).ljust(w) for c, w in zip(r, widths)))
    return "\n".join(out)


def _spread(s):
    if not s or s.get("median") is None or len(s["values"]) < 2:
        return ""
    return f" ±{(s['max'] - s['min']) / 2 / s['median'] * 100:.0f}%"


def format_table(result: dict) -> str:
    """The human table: one line per scene x device (medians; ± = half the min-max spread)."""
    headers = ["scene", "device", "integrator", "res", "spp", "samples/s", "rays/s", "rays/spl", "pass",
               "build cold", "build warm", "load", "BVH", "pack", "dev mem", "peak RSS"]
    rows = []
    for r in result["results"]:
        if r["status"] != "ok":
            rows.append([r["scene"], r["device"], r.get("integrator") or "-", "", "", r["status"]]
                        + [""] * (len(headers) - 6))
            continue
        b = r.get("build", {})
        rays = r.get("rays")
        rows.append([
            r["scene"], r["device"], r["integrator"], f"{r['width']}x{r['height']}", r["spp"],
            _fmt_rate(_med(r["samples_per_second"])) + _spread(r["samples_per_second"]),
            _fmt_rate(_med(r.get("rays_per_second"))),
            "-" if not rays else f"{rays['per_sample']:.2f}",
            _fmt_s(_med(r["pass_seconds"]), ms=True),
            _fmt_s(b.get("cold_total")), _fmt_s(b.get("warm_total")),
            _fmt_s(r["load_seconds"]), _fmt_s(r["bvh_build_seconds"]), _fmt_s(r["pack_seconds"]),
            _fmt_bytes(r["device_memory_bytes"]), _fmt_bytes(r["host_peak_rss_bytes"]),
        ])
    text = _table(headers, rows)
    host = result.get("host", {})
    notes = [f"clrender {result['clrender_version']} ({result['git_revision'][:12]}), {result['timestamp']}, "
             f"load average {host.get('loadavg_start')} -> {host.get('loadavg_end')}; "
             f"medians of {result['settings']['repeat']} repeats, ± = half the min-max spread; "
             "build = program build + first launch (cold: fresh process, empty PoCL cache)"]
    seen = set()
    for r in result["results"]:
        if r["status"] != "ok" and (r["device"], r["reason"]) not in seen:
            seen.add((r["device"], r["reason"]))
            notes.append(f"{r['status']}: {r['device']}: {r['reason']}")
    for r in result["results"]:
        for c in (r.get("convergence") or [])[-1:]:
            notes.append(f"{r['scene']} on {r['device']}: relMSE {c['relmse']:.4g} after {c['spp']} spp, "
                         f"{c['seconds']:.3g} s")
    return text + "\n" + "\n".join(notes)


# ------------------------------------------------------------------------------------------------------------
# Compare
# ------------------------------------------------------------------------------------------------------------
_COMPARED = (("samples/s", lambda r: _med(r.get("samples_per_second"))),
             ("rays/s", lambda r: _med(r.get("rays_per_second"))),
             ("pass time", lambda r: _med(r.get("pass_seconds"))),
             ("build cold", lambda r: (r.get("build") or {}).get("cold_total")),
             ("build warm", lambda r: (r.get("build") or {}).get("warm_total")),
             ("BVH", lambda r: r.get("bvh_build_seconds")))


def compare(a: dict, b: dict) -> list[dict]:
    """Pair rows of two results by (scene hash, integrator), else (scene name, integrator); within a key, rows
    on the same device name pair first, the rest in order. Each pair gets ratios B/A."""
    oka = [r for r in a["results"] if r["status"] == "ok"]
    okb = [r for r in b["results"] if r["status"] == "ok"]
    pairs, used_b = [], set()
    for keyf in (lambda r: (r.get("scene_hash"), r["integrator"]), lambda r: (r["scene"], r["integrator"])):
        for ra in oka:
            if any(ra is p[0] for p in pairs):
                continue
            cands = [rb for rb in okb if id(rb) not in used_b and keyf(rb) == keyf(ra)]
            if not cands:
                continue
            same = [rb for rb in cands if rb["device"] == ra["device"]]
            rb = (same or cands)[0]
            used_b.add(id(rb))
            pairs.append((ra, rb))
    out = []
    for ra, rb in pairs:
        ratios = {}
        for name, f in _COMPARED:
            va, vb = f(ra), f(rb)
            ratios[name] = (vb / va) if va and vb is not None else None
        note = []
        if ra.get("scene_hash") != rb.get("scene_hash"):
            note.append("scene files differ")
        if (ra["width"], ra["height"], ra["spp"]) != (rb["width"], rb["height"], rb["spp"]):
            note.append("resolution/spp differ")
        out.append({"scene": ra["scene"], "integrator": ra["integrator"], "device_a": ra["device"],
                    "device_b": rb["device"], "ratios": ratios, "note": "; ".join(note)})
    return out


def format_compare(a: dict, b: dict, name_a="A", name_b="B") -> str:
    pairs = compare(a, b)
    if not pairs:
        return f"no matching (scene, integrator) rows in {name_a} and {name_b}"
    headers = ["scene", "integrator", "device A -> B"] + [n for n, _ in _COMPARED] + ["note"]
    rows = []
    for p in pairs:
        dev = p["device_a"] if p["device_a"] == p["device_b"] else f"{p['device_a']} -> {p['device_b']}"
        rows.append([p["scene"], p["integrator"], dev]
                    + ["-" if p["ratios"][n] is None else f"{p['ratios'][n]:.3f}x" for n, _ in _COMPARED]
                    + [p["note"]])
    head = (f"ratios B/A (A = {name_a}: {a.get('git_revision', '?')[:12]} {a.get('timestamp', '')}; "
            f"B = {name_b}: {b.get('git_revision', '?')[:12]} {b.get('timestamp', '')}). "
            "samples/s and rays/s: > 1 = B faster; times: < 1 = B faster")
    return head + "\n" + _table(headers, rows)


# ------------------------------------------------------------------------------------------------------------
# Plot
# ------------------------------------------------------------------------------------------------------------
def plot(result: dict, path) -> Path:
    """Bars of samples/s per scene and device (with the min-max spread); with convergence data, a second
    panel of relMSE against render time (log-log)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise ClrenderError('--plot needs matplotlib: pip install "clrender[plot]"') from None
    ok = [r for r in result["results"] if r["status"] == "ok"]
    curves = [r for r in ok if r.get("convergence")]
    fig, axes = plt.subplots(1, 2 if curves else 1, figsize=(12 if curves else 7, 4.5), squeeze=False)
    ax = axes[0][0]
    scenes = list(dict.fromkeys(r["scene"] for r in ok))
    devices = list(dict.fromkeys(r["device"] for r in ok))
    width = 0.8 / max(len(devices), 1)
    for j, d in enumerate(devices):
        xs, ys, lo, hi = [], [], [], []
        for i, s in enumerate(scenes):
            r = next((r for r in ok if r["scene"] == s and r["device"] == d), None)
            if r is None:
                continue
            sp = r["samples_per_second"]
            xs.append(i + (j - (len(devices) - 1) / 2) * width)
            ys.append(sp["median"] / 1e6)
            lo.append((sp["median"] - sp["min"]) / 1e6)
            hi.append((sp["max"] - sp["median"]) / 1e6)
        ax.bar(xs, ys, width, yerr=[lo, hi], capsize=3, label=d)
        for x, y, h in zip(xs, ys, hi):
            ax.annotate(f"{y:.2f}", (x, y + h), ha="center", va="bottom", fontsize=8,
                        xytext=(0, 2), textcoords="offset points")
    ax.set_xticks(range(len(scenes)))
    ax.set_xticklabels(scenes, rotation=15)
    ax.set_ylabel("M samples / s (median, min-max)")
    ax.set_title(f"clrender {result['clrender_version']} {result['git_revision'][:10]}")
    if devices:
        ax.legend(fontsize=8)
    if curves:
        ax2 = axes[0][1]
        for r in curves:
            c = r["convergence"]
            ax2.loglog([p["seconds"] for p in c], [p["relmse"] for p in c], "o-", ms=3,
                       label=f"{r['scene']} / {r['device']}")
        ax2.set_xlabel("render time (s)")
        ax2.set_ylabel("relMSE")
        ax2.set_title("convergence")
        ax2.grid(True, which="both", alpha=0.3)
        ax2.legend(fontsize=8)
    fig.tight_layout()
    from .film import _atomic_write

    path = _atomic_write(Path(path), lambda tmp: fig.savefig(tmp, dpi=110))  # a reader never sees half a plot
    plt.close(fig)
    return path
