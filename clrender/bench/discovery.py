"""Which scenes and devices `clrender bench` measures: the default scene set (found in the checkout), a scene's
content hash, loading a scene as `clrender render` does, and the OpenCL devices with whether each builds kernels."""
from __future__ import annotations

import time
from pathlib import Path

from ..errors import ClrenderError
from ..scenesource import SceneSource, resolve

#: the default benchmark set, relative to the repository's scenes/ folder
DEFAULT_SCENES = ("cornell/cornell_path_mis.xml", "mis/mis_path_mis.xml", "largemesh/largemesh_path_mis.xml")


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
    candidates.append(Path(__file__).resolve().parents[2] / "scenes")
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




def scene_hash(path) -> str:
    """The scene's content hash, the one farm parts and cluster workers carry (SceneSource.content_hash)."""
    return SceneSource(resolve(path)).content_hash()


def load_bench_scene(path, integrator: str | None = None, width: int | None = None, height: int | None = None):
    """Load a scene as `clrender render` does (clrender.load_scene), optionally with another integrator (made by
    the registry, as if the file named it) or resolution. Returns (scene, spec, seconds)."""
    from ..loader import load_scene
    from ..scene.registry import instantiate

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
    from ..device.context import build_check, choose_device, is_simulator, list_devices

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
