"""clrender and Mitsuba 3 side by side: the same twin scenes, rendered by both in one run, interleaved.

    python benchmarks/vs_mitsuba.py [--spp 64] [--repeat 5] [--reference-spp 1024] [--res 256] [--json OUT]
                                    [--only NAME ...] [--quick] [--no-count-rays]

`--quick` is for trying it (spp 4, repeat 1, reference 16 spp, 128x128; its figures mean nothing).

Mitsuba is a benchmark-only dependency (never needed to install, run or test clrender): `pip install mitsuba`;
its LLVM backend needs libLLVM >= 16 on this Debian (`apt-get install libllvm19`), found through
DRJIT_LIBLLVM_PATH (set below when the file exists). Each twin is written once from one neutral description
(geometry as OBJ files both read, the same camera, BSDFs and light) into our Nori XML and Mitsuba 3's XML:
- camera: upstream Nori's perspective and Mitsuba's share the convention (camera +x on the image's left) and
  a horizontal fov; box reconstruction filter, independent sampler;
- diffuse = diffuse; mirror = Mitsuba's `conductor` with material "none" (a perfect mirror); dielectric =
  `dielectric` with the same IORs; area lights are one-sided on the side of their normals in both;
- integrator: our `path_mis` and Mitsuba's `path`, both without a depth limit. Russian roulette differs (ours
  Nori's, from depth 3; Mitsuba's from depth 5), so samples/s alone is not the whole story: the script also
  reports the time each needs to reach the same relMSE against a long reference (Mitsuba's, `--reference-spp`).

The twins `cornell_spheres` and `cornell` are written that way (Nori XML against Mitsuba XML: two integrators).
clrender also reads Mitsuba 3's XML, so the others are ONE Mitsuba file read by both, with Mitsuba's `path`
integrator (its MIS and its roulette from depth 5) on both sides, the fairest comparison:
- `cornell_spheres_mi`: the Cornell twin's Mitsuba file;
- `rough_plates`: four metal plates from nearly smooth to rough under four spherical lights of equal power and
  very different sizes (the MIS test case; described in our own words below);
- `large_mesh`: a bumpy sphere of 1,003,520 triangles (scenes/scenekit's blob, written as binary PLY) on a
  diffuse floor under a square area light;
- `furnace`: a diffuse sphere (albedo 0.8) in a constant sky of radiance 1: the sphere's pixels are 0.8 and the
  others 1, exactly; both renderers' region means are reported against those values.

Figures per twin and renderer (medians of --repeat interleaved renders after a warm-up): render seconds and
samples/s (render only, in process), whole-process seconds (a fresh `clrender render` / `python -c` Mitsuba
process: start, load, build, render, write), relMSE at --spp and the time to equal error (seconds x relMSE:
the render time at which each reaches the other's error, assuming error ~ 1/time). clrender's rays per sample
come from one more render of the same samples (seed) by a program built with -DCLRENDER_COUNT_RAYS, after the
timed ones; its rays/s = rays per sample x the timed samples/s (Mitsuba's: not known, null). Written to
benchmarks/results/vs_mitsuba-<date>.json, printed as a table and plotted (clrender / Mitsuba ratios) into the
PNG of the same name.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
if "DRJIT_LIBLLVM_PATH" not in os.environ and Path(LLVM).is_file():
    os.environ["DRJIT_LIBLLVM_PATH"] = LLVM

# ------------------------------------------------------------------------------------------------ twin scenes
WALLS = {  # quads (counter-clockwise seen from inside the box, normals inward), albedo
    "floor": ([(-1, 0, 1), (1, 0, 1), (1, 0, -1), (-1, 0, -1)], (0, 1, 0), (0.725, 0.71, 0.68)),
    "ceiling": ([(-1, 2, -1), (1, 2, -1), (1, 2, 1), (-1, 2, 1)], (0, -1, 0), (0.725, 0.71, 0.68)),
    "back": ([(-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1)], (0, 0, 1), (0.725, 0.71, 0.68)),
    "left": ([(-1, 0, 1), (-1, 0, -1), (-1, 2, -1), (-1, 2, 1)], (1, 0, 0), (0.63, 0.065, 0.05)),
    "right": ([(1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1)], (-1, 0, 0), (0.14, 0.45, 0.091)),
}
LIGHT = ([(-0.25, 1.98, -0.25), (0.25, 1.98, -0.25), (0.25, 1.98, 0.25), (-0.25, 1.98, 0.25)], (0, -1, 0))
CAMERA = dict(origin=(0, 1, 3.9), target=(0, 1, 0), up=(0, 1, 0), fov=39.3, width=256, height=256)


def write_quad(path, corners, normal):
    """An OBJ quad with vertex normals, wound so that its face normal agrees with `normal`."""
    c = np.asarray(corners, float)
    n = np.asarray(normal, float)
    if np.dot(np.cross(c[1] - c[0], c[2] - c[0]), n) < 0:
        c = c[::-1]
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in c] + [f"vn {n[0]:g} {n[1]:g} {n[2]:g}"]
    lines.append("f 1//1 2//1 3//1 4//1")
    Path(path).write_text("\n".join(lines) + "\n")


def twin_cornell(d: Path, spp: int, with_spheres: bool = True, res: int = 256) -> dict:
    """The Cornell box with a mirror sphere and a glass sphere (tessellated, smooth normals)."""
    d.mkdir(parents=True, exist_ok=True)
    shapes = []
    for name, (c, n, rho) in WALLS.items():
        write_quad(d / f"{name}.obj", c, n)
        shapes.append(dict(file=f"{name}.obj", bsdf=("diffuse", rho)))
    write_quad(d / "light.obj", *LIGHT)
    shapes.append(dict(file="light.obj", bsdf=("diffuse", (0, 0, 0)), radiance=(17, 12, 4)))
    if with_spheres:
        sphere = (ROOT / "scenes" / "meshes" / "unit_sphere.obj").read_text()
        (d / "sphere.obj").write_text(sphere)
        shapes.append(dict(file="sphere.obj", bsdf=("mirror",), scale=0.35, translate=(-0.45, 0.35, -0.3)))
        shapes.append(dict(file="sphere.obj", bsdf=("dielectric", 1.5046, 1.000277), scale=0.35,
                           translate=(0.45, 0.35, 0.3)))
    return dict(name="cornell_spheres" if with_spheres else "cornell", shapes=shapes,
                camera=dict(CAMERA, width=res, height=res), spp=spp)


def _f3(v):
    return ", ".join(f"{x:g}" for x in v)


# The two formats differ only in names: one writer, one table of them.
FORMATS = {
    "nori": dict(
        root="<scene>", integrator='<integrator type="path_mis"/>', sensor="camera", to_world="toWorld",
        fov_axis="", sampler='<sampler type="independent"><integer name="sampleCount" value="{spp}"/></sampler>',
        film='<integer name="width" value="{w}"/><integer name="height" value="{h}"/><rfilter type="box"/>',
        shape="mesh", diffuse='<bsdf type="diffuse"><color name="albedo" value="{rho}"/></bsdf>',
        mirror='<bsdf type="mirror"/>',
        dielectric='<bsdf type="dielectric"><float name="intIOR" value="{i}"/><float name="extIOR" value="{e}"/></bsdf>',
        area='<emitter type="area"><color name="radiance" value="{L}"/></emitter>', sampler_in_sensor=False),
    "mitsuba": dict(
        root='<scene version="3.0.0">', integrator='<integrator type="path"><integer name="max_depth" value="-1"/></integrator>',
        sensor="sensor", to_world="to_world", fov_axis='<string name="fov_axis" value="x"/>',
        sampler='<sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>',
        film='<film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>'
             '<rfilter type="box"/></film>',
        shape="shape", diffuse='<bsdf type="diffuse"><rgb name="reflectance" value="{rho}"/></bsdf>',
        mirror='<bsdf type="conductor"><string name="material" value="none"/></bsdf>',
        dielectric='<bsdf type="dielectric"><float name="int_ior" value="{i}"/><float name="ext_ior" value="{e}"/></bsdf>',
        area='<emitter type="area"><rgb name="radiance" value="{L}"/></emitter>', sampler_in_sensor=True),
}


def scene_xml(t: dict, fmt: str) -> str:
    """The twin `t` in Nori's XML (fmt "nori") or Mitsuba 3's ("mitsuba")."""
    f = FORMATS[fmt]
    c = t["camera"]
    sampler = f["sampler"].format(spp=t["spp"])
    out = [f["root"], "  " + f["integrator"]]
    if not f["sampler_in_sensor"]:
        out.append("  " + sampler)
    out += [f'  <{f["sensor"]} type="perspective">',
            f'    <float name="fov" value="{c["fov"]}"/>{f["fov_axis"]}',
            f'    <transform name="{f["to_world"]}"><lookat origin="{_f3(c["origin"])}" target="{_f3(c["target"])}" '
            f'up="{_f3(c["up"])}"/></transform>']
    if f["sampler_in_sensor"]:
        out.append("    " + sampler)
    out += ["    " + f["film"].format(w=c["width"], h=c["height"]), f'  </{f["sensor"]}>']
    for s in t["shapes"]:
        out.append(f'  <{f["shape"]} type="obj">')
        out.append(f'    <string name="filename" value="{s["file"]}"/>')
        if "scale" in s:
            out.append(f'    <transform name="{f["to_world"]}"><scale value="{s["scale"]}"/>'
                       f'<translate value="{_f3(s["translate"])}"/></transform>')
        b = s["bsdf"]
        if b[0] == "diffuse":
            out.append("    " + f["diffuse"].format(rho=_f3(b[1])))
        elif b[0] == "mirror":
            out.append("    " + f["mirror"])
        else:
            out.append("    " + f["dielectric"].format(i=b[1], e=b[2]))
        if "radiance" in s:
            out.append("    " + f["area"].format(L=_f3(s["radiance"])))
        out.append(f'  </{f["shape"]}>')
    out.append("</scene>")
    return "\n".join(out) + "\n"


# ---------------------------------------------------------------- twins in one Mitsuba 3 file that both read
# clrender reads Mitsuba 3's XML itself, so these twins are ONE file rendered by both renderers, with Mitsuba's
# `path` integrator semantics (power-heuristic MIS, roulette from depth 5) on both sides.
def _mi_xml(cam: dict, spp: int, body: list[str], comment: str) -> str:
    """A Mitsuba 3 scene: `path` without a depth limit, a perspective camera (horizontal fov), a box filter."""
    head = [f"<!-- {comment} (written by benchmarks/vs_mitsuba.py) -->", '<scene version="3.0.0">',
            '  <integrator type="path"><integer name="max_depth" value="-1"/></integrator>',
            '  <sensor type="perspective">',
            f'    <float name="fov" value="{cam["fov"]}"/><string name="fov_axis" value="x"/>',
            f'    <transform name="to_world"><lookat origin="{_f3(cam["origin"])}" target="{_f3(cam["target"])}" '
            f'up="{_f3(cam["up"])}"/></transform>',
            f'    <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>',
            f'    <film type="hdrfilm"><integer name="width" value="{cam["width"]}"/>'
            f'<integer name="height" value="{cam["height"]}"/><rfilter type="box"/></film>',
            "  </sensor>"]
    return "\n".join(head + ["  " + b for b in body] + ["</scene>"]) + "\n"


def _matrix(m) -> str:
    return '<transform name="to_world"><matrix value="' + " ".join(f"{x:.9g}" for x in np.asarray(m).ravel()) \
        + '"/></transform>'


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def _facing_rectangle(center, half_x, half_y, normal):
    """to_world of Mitsuba's `rectangle` ([-1, 1]^2 in z = 0, normal +z): its x axis stays horizontal (world x)
    and its normal is `normal`."""
    n = _unit(normal)
    x = _unit(np.cross((0, 1, 0), n)) if abs(n[1]) < 0.999 else np.array([1.0, 0, 0])
    y = np.cross(n, x)  # x, y, n right-handed
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x * half_x, y * half_y, n, center
    return m


# The rough-plates MIS scene, described in our own words: four long, narrow metal plates climb away from the
# camera like the steps of a stair, each tilted so that it mirrors the row of lights behind them towards the
# camera; the plates go from nearly smooth (nearest) to quite rough (farthest); four spherical lights of
# equal power but very different sizes (radius 0.03 to 0.9, radiance ~ 1 / radius^2) hang in a row above and
# behind; a grey floor and a dim constant sky. Emitter sampling is noisy where smooth plates reflect the large
# lights, BSDF sampling where rough plates reflect the small ones: the scene rewards MIS.
PLATES_CAMERA = dict(origin=(0, 3.2, 9.5), target=(0, 1.4, 0), up=(0, 1, 0), fov=42)
PLATES = [  # centre, GGX alpha
    ((0, 0.45, 2.6), 0.005), ((0, 0.95, 1.3), 0.02), ((0, 1.55, 0.0), 0.08), ((0, 2.25, -1.3), 0.25)]
PLATE_HALF = (4.0, 0.42)
PLATE_LIGHTS = [  # centre, radius, radiance
    ((-3.75, 4.2, -3.5), 0.03, 1000.0), ((-1.25, 4.2, -3.5), 0.1, 90.0), ((1.25, 4.2, -3.5), 0.3, 10.0),
    ((3.75, 4.2, -3.5), 0.9, 1.1)]


def twin_rough_plates(d: Path, spp: int, res: int = 256) -> dict:
    d.mkdir(parents=True, exist_ok=True)
    cam = dict(PLATES_CAMERA, width=res, height=res)
    aim = np.mean([c for c, _, _ in PLATE_LIGHTS], axis=0)
    body = ['<emitter type="constant"><rgb name="radiance" value="0.03"/></emitter>',
            '<shape type="rectangle">' + _matrix(_facing_rectangle((0, 0, 0), 12, 12, (0, 1, 0)))
            + '<bsdf type="diffuse"><rgb name="reflectance" value="0.35"/></bsdf></shape>']
    for c, alpha in PLATES:
        c = np.asarray(c, float)
        n = _unit(_unit(np.asarray(cam["origin"]) - c) + _unit(aim - c))  # the half vector: mirrors aim to camera
        body.append('<shape type="rectangle">' + _matrix(_facing_rectangle(c, *PLATE_HALF, n))
                    + f'<bsdf type="roughconductor"><string name="material" value="Al"/>'
                      f'<string name="distribution" value="ggx"/><float name="alpha" value="{alpha}"/></bsdf>'
                      "</shape>")
    for c, r, L in PLATE_LIGHTS:
        body.append(f'<shape type="sphere"><point name="center" value="{_f3(c)}"/><float name="radius" '
                    f'value="{r}"/><emitter type="area"><rgb name="radiance" value="{L:g}"/></emitter></shape>')
    xml = _mi_xml(cam, spp, body, "rough plates: MIS with lights of very different sizes")
    return dict(name="rough_plates", xml=xml, camera=cam, spp=spp)


def _scenes_build():
    """The repository's scene kit (scenes/scenekit: its geodesic 'blob' mesh and binary PLY writer), as a namespace."""
    import types

    scenes = str(ROOT / "scenes")
    if scenes not in sys.path:
        sys.path.insert(0, scenes)
    from scenekit.files import write_ply
    from scenekit.geometry import blob

    return types.SimpleNamespace(blob=blob, write_ply=write_ply)


LARGE_MESH_SUBDIVISIONS = 224  # 20 * 224^2 = 1,003,520 triangles


def twin_large_mesh(d: Path, spp: int, res: int = 256, subdivisions: int = LARGE_MESH_SUBDIVISIONS) -> dict:
    """A bumpy sphere of 20 n^2 triangles (smooth vertex normals; binary PLY, which both read) on a diffuse floor
    under a square area light facing down."""
    d.mkdir(parents=True, exist_ok=True)
    b = _scenes_build()
    V, N, F = b.blob(subdivisions)
    b.write_ply(d / "blob.ply", V, N, F, comment="vs_mitsuba large_mesh")
    cam = dict(origin=(0, 2.4, 5.2), target=(0, 1.0, 0), up=(0, 1, 0), fov=45, width=res, height=res)
    body = ['<shape type="rectangle">' + _matrix(_facing_rectangle((0, 0, 0), 8, 8, (0, 1, 0)))
            + '<bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>',
            '<shape type="rectangle">' + _matrix(_facing_rectangle((0, 4.0, 0.5), 0.8, 0.8, (0, -1, 0)))
            + '<emitter type="area"><rgb name="radiance" value="14"/></emitter></shape>',
            '<shape type="ply"><string name="filename" value="blob.ply"/>'
            '<transform name="to_world"><translate value="0, 1.2, 0"/></transform>'
            '<bsdf type="diffuse"><rgb name="reflectance" value="0.75, 0.55, 0.35"/></bsdf></shape>']
    xml = _mi_xml(cam, spp, body, f"large mesh: {len(F):,} triangles under an area light")
    return dict(name="large_mesh", xml=xml, camera=cam, spp=spp, triangles=int(len(F)))


# The furnace: a diffuse sphere of albedo FURNACE_ALBEDO in a constant environment of radiance 1, centred on
# the optical axis. A convex object never sees itself, so every ray leaving it escapes: the sphere's pixels
# are exactly albedo x 1, the others exactly 1; pixels the silhouette crosses are a mix (left out).
FURNACE_ALBEDO = 0.8
FURNACE_CAMERA = dict(origin=(0, 0, 4), target=(0, 0, 0), up=(0, 1, 0), fov=40)
FURNACE_RADIUS = 1.0


def twin_furnace(d: Path, spp: int, res: int = 256) -> dict:
    d.mkdir(parents=True, exist_ok=True)
    cam = dict(FURNACE_CAMERA, width=res, height=res)
    body = ['<emitter type="constant"><rgb name="radiance" value="1"/></emitter>',
            f'<shape type="sphere"><float name="radius" value="{FURNACE_RADIUS}"/>'
            f'<bsdf type="diffuse"><rgb name="reflectance" value="{FURNACE_ALBEDO}"/></bsdf></shape>']
    xml = _mi_xml(cam, spp, body, f"furnace: a diffuse sphere (albedo {FURNACE_ALBEDO}) in a constant sky")
    return dict(name="furnace", xml=xml, camera=cam, spp=spp, analytic=furnace_masks(cam))


def furnace_masks(cam: dict) -> dict:
    """Pixels whose whole footprint lies inside the sphere's silhouette (analytic value: the albedo) and wholly
    outside it (1). On the image plane at distance 1 the silhouette of a sphere centred on the axis is a circle of
    radius r / sqrt(d^2 - r^2); a pixel covers a square of side 2 tan(fov / 2) / width (fov_axis x)."""
    w, h = cam["width"], cam["height"]
    dist = float(np.linalg.norm(np.subtract(cam["origin"], cam["target"])))
    R = FURNACE_RADIUS / np.sqrt(dist * dist - FURNACE_RADIUS ** 2)
    s = 2 * np.tan(np.radians(cam["fov"]) / 2) / w
    x0 = (np.arange(w) - w / 2) * s  # left edges of the pixel columns, rows alike (square pixels)
    y0 = (np.arange(h) - h / 2) * s
    X0, Y0 = np.meshgrid(x0, y0)
    far = np.maximum(np.abs(X0), np.abs(X0 + s)) ** 2 + np.maximum(np.abs(Y0), np.abs(Y0 + s)) ** 2
    near = np.clip(0, X0, X0 + s) ** 2 + np.clip(0, Y0, Y0 + s) ** 2  # nearest point of the square to the axis
    return {"inside": np.sqrt(far) < R * (1 - 1e-4), "outside": np.sqrt(near) > R * (1 + 1e-4),
            "values": (FURNACE_ALBEDO, 1.0)}


def furnace_report(img, masks) -> dict:
    """Region means of one image (channel-averaged) against the analytic values, with the standard error of each
    mean (pixels are independent estimates)."""
    y = img.reshape(img.shape[0], img.shape[1], -1).mean(axis=2)
    out = {}
    for key, value in zip(("inside", "outside"), masks["values"]):
        v = y[masks[key]]
        out[key] = {"analytic": value, "mean": float(v.mean()), "stderr": float(v.std(ddof=1) / np.sqrt(v.size)),
                    "pixels": int(v.size)}
    return out


def twin_cornell_mi(d: Path, spp: int, res: int = 256) -> dict:
    """The Cornell twin's Mitsuba XML, rendered by clrender too (the same integrator on both sides)."""
    t = twin_cornell(d, spp, res=res)
    return dict(t, name="cornell_spheres_mi", xml=scene_xml(t, "mitsuba"))


# -------------------------------------------------------------------------------------------------- renderers
class Clrender:
    name = "clrender"

    def __init__(self, xml: Path, device: str | None = None):
        import clrender
        from clrender.renderer import Renderer

        self.xml, self.device = xml, device
        self.renderer = Renderer(clrender.load_scene(xml), device=device)
        self.renderer.render(spp=1)  # build + first launch

    def render(self, spp: int, seed: int):
        film = self.renderer.render(spp=spp, seed=seed)
        return film.image.astype(np.float64), film.stats.seconds

    def process_cmd(self, spp: int, out: Path):
        dev = ["--device", str(self.device)] if self.device is not None else []
        return [sys.executable, "-m", "clrender.cli", "render", str(self.xml), "--spp", str(spp), "-q", "-o", str(out),
                *dev]

    def count_rays(self, spp: int, seed: int) -> dict:
        """Rays one render of these samples traces, from a second program built with -DCLRENDER_COUNT_RAYS (the
        timed program has no counting code), on the same packed scene."""
        from clrender.renderer import Renderer

        rc = Renderer(self.renderer.scene, device=self.device, buffers=self.renderer.buffers, count_rays=True)
        cam, closest, shadow = rc.render(spp=spp, seed=seed).stats.rays
        total = cam + closest + shadow
        return {"camera": cam, "closest": closest, "shadow": shadow, "total": total,
                "per_sample": total / (rc.n_pixels * spp)}


class Mitsuba:
    def __init__(self, xml: Path, variant: str = "llvm_ad_rgb"):
        import mitsuba as mi

        mi.set_variant(variant)
        self.mi, self.xml, self.variant, self.name = mi, xml, variant, f"mitsuba {variant}"
        self.scene = mi.load_file(str(xml))
        self.render(1, 0)  # JIT warm-up

    def render(self, spp: int, seed: int):
        import drjit as dr

        t0 = time.perf_counter()
        img = self.mi.render(self.scene, spp=spp, seed=seed)
        dr.eval(img)
        dr.sync_thread()
        return np.array(img, np.float64), time.perf_counter() - t0

    def process_cmd(self, spp: int, out: Path):
        code = (f"import mitsuba as mi; mi.set_variant({self.variant!r}); "
                f"s = mi.load_file({str(self.xml)!r}); img = mi.render(s, spp={spp}); "
                f"mi.util.write_bitmap({str(out)!r}, img)")
        return [sys.executable, "-c", code]


def relmse(img, ref):
    return float(np.mean((img - ref) ** 2 / (ref * ref + 1e-2)))


def write_twin(t: dict, d: Path) -> dict:
    """The twin's scene files in folder `d`: {"clrender": path, "mitsuba": path}."""
    if "xml" in t:  # one Mitsuba 3 file, read by both
        (d / "scene.xml").write_text(t["xml"])
        return {"clrender": d / "scene.xml", "mitsuba": d / "scene.xml"}
    # our Nori XML and Mitsuba 3's, from one description
    files = {"clrender": d / "clrender.xml", "mitsuba": d / "mitsuba.xml"}
    files["clrender"].write_text(scene_xml(t, "nori"))
    files["mitsuba"].write_text(scene_xml(t, "mitsuba"))
    return files


def bench_twin(t: dict, d: Path, spp: int, repeat: int, ref_spp: int, say, count_rays: bool = True,
               device: str | None = None, variant: str = "llvm_ad_rgb") -> dict:
    files = write_twin(t, d)
    say(f"{t['name']}: loading, building, warming up")
    rs = [Clrender(files["clrender"], device), Mitsuba(files["mitsuba"], variant)]
    say(f"{t['name']}: reference ({ref_spp} spp, Mitsuba)")
    ref, _ = rs[1].render(ref_spp, 12345)
    n = t["camera"]["width"] * t["camera"]["height"]
    rows = {r.name: {"render_seconds": [], "relmse": [], "process_seconds": [], "mean_rgb": []} for r in rs}
    for k in range(repeat):
        for r in rs:  # interleaved: the machine's state changes affect both alike
            img, secs = r.render(spp, 100 + k)
            rows[r.name]["render_seconds"].append(secs)
            rows[r.name]["relmse"].append(relmse(img, ref))
            rows[r.name]["mean_rgb"].append(img.reshape(-1, 3).mean(axis=0).tolist())
            if "analytic" in t:
                rows[r.name].setdefault("furnace", []).append(furnace_report(img, t["analytic"]))
        for r in rs:
            with tempfile.TemporaryDirectory() as tmp:
                t0 = time.perf_counter()
                subprocess.run(r.process_cmd(spp, Path(tmp) / "x.exr"), check=True, capture_output=True)
                rows[r.name]["process_seconds"].append(time.perf_counter() - t0)
        say(f"{t['name']}: round {k + 1}/{repeat}")
    out = {}
    for name, v in rows.items():
        secs = statistics.median(v["render_seconds"])
        err = statistics.median(v["relmse"])
        # the twins must converge to the same image: mean over the renders vs the reference's, per channel
        agree = (np.mean(v["mean_rgb"], axis=0) / ref.reshape(-1, 3).mean(axis=0)).tolist()
        out[name] = {"render_seconds": secs, "samples_per_second": n * spp / secs, "relmse": err,
                     "image_mean_over_reference": agree,
                     "time_x_error": secs * err, "process_seconds": statistics.median(v["process_seconds"]),
                     "rays": None, "rays_per_sample": None, "rays_per_second": None, "all": v}
        if "analytic" in t:  # regions pooled over the renders: their means and standard errors
            out[name]["furnace"] = {
                key: {"analytic": v["furnace"][0][key]["analytic"],
                      "mean": float(np.mean([f[key]["mean"] for f in v["furnace"]])),
                      "stderr": float(np.sqrt(np.sum([f[key]["stderr"] ** 2 for f in v["furnace"]])) / repeat),
                      "pixels": v["furnace"][0][key]["pixels"]} for key in ("inside", "outside")}
    if count_rays:  # a separate render with the counting program, after the timed ones (Mitsuba's: unknown)
        say(f"{t['name']}: counting clrender's rays")
        rays = rs[0].count_rays(spp, 100)
        c = out["clrender"]
        c.update(rays=rays, rays_per_sample=rays["per_sample"],
                 rays_per_second=rays["per_sample"] * c["samples_per_second"])
    out["twin"] = {"files": "one Mitsuba 3 XML" if "xml" in t else "Nori XML (clrender) + Mitsuba 3 XML",
                   "width": t["camera"]["width"], "height": t["camera"]["height"],
                   **({"triangles": t["triangles"]} if "triangles" in t else {})}
    a, b = out["clrender"], out[rs[1].name]
    out["ratios"] = {"samples_per_second": a["samples_per_second"] / b["samples_per_second"],
                     "time_to_equal_error": b["time_x_error"] / a["time_x_error"],
                     "whole_process": b["process_seconds"] / a["process_seconds"]}
    return out


TWINS = {  # name -> maker(folder, spp, res); the default order of a run
    "cornell_spheres": lambda d, spp, res: twin_cornell(d, spp, res=res),
    "cornell": lambda d, spp, res: twin_cornell(d, spp, with_spheres=False, res=res),
    "cornell_spheres_mi": twin_cornell_mi,
    "rough_plates": twin_rough_plates,
    "large_mesh": twin_large_mesh,
    "furnace": twin_furnace,
}
QUICK = dict(spp=4, repeat=1, reference_spp=16, res=128)
FULL = dict(spp=64, repeat=5, reference_spp=1024, res=256)


def made_twins(tmp, only, spp: int, res: int):
    """(name, folder, twin description) of each twin (those in `only`, if given), made in its own folder of tmp."""
    for name, make in TWINS.items():
        if only and name not in only:
            continue
        d = Path(tmp) / name
        yield name, d, make(d, spp, res)


def cornell_twin_xml(folder: Path, spp: int = 64) -> Path:
    """The Cornell twin in our Nori XML, written into `folder` (the default scene of the A/B and profiling
    tools in this folder)."""
    folder = Path(folder)
    xml = folder / "clrender.xml"
    xml.write_text(scene_xml(twin_cornell(folder, spp), "nori"))
    return xml


def scene_or_cornell_twin(scene: str | None, folder: Path) -> Path:
    """The scene XML of an A/B or profiling tool: `scene` when given (its --scene), else the Cornell twin written
    into `folder` (which must outlive the run)."""
    return Path(scene) if scene else cornell_twin_xml(folder)


def cpu_name() -> str:
    """The CPU's model name (for results files): /proc/cpuinfo, else what platform knows."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


# ------------------------------------------------------------------------------------------------------- plot
PLOT_BARS = (("samples_per_second", "samples/s", (70, 130, 180)),
             ("time_to_equal_error", "time to equal error", (230, 140, 40)),
             ("whole_process", "whole process", (120, 170, 90)))


def plot(doc: dict, path: Path) -> Path:
    """Per twin, the clrender / Mitsuba ratios as horizontal bars on a log axis (1 = as fast as Mitsuba;
    right of it = faster), drawn with Pillow (a clrender dependency) into a PNG."""
    from PIL import Image, ImageDraw, ImageFont

    def font(size):
        try:
            return ImageFont.load_default(size=size)
        except TypeError:  # Pillow < 10.1: one bitmap size
            return ImageFont.load_default()

    f, fs = font(14), font(11)
    names = list(doc["results"])
    bar, gap, left, right, top = 14, 14, 170, 40, 58
    W = 820
    H = top + len(names) * (len(PLOT_BARS) * bar + gap) + 50
    img = Image.new("RGB", (W, H), "white")
    g = ImageDraw.Draw(img)
    lo, hi = 1 / 8, 8.0  # log2 axis from 1/8x to 8x

    def x_of(q):
        return left + (W - left - right) * (np.log2(np.clip(q, lo, hi)) - np.log2(lo)) / np.log2(hi / lo)

    trial = "  (--quick: a trial)" if doc.get("quick") else ""
    variant = doc.get("mitsuba_variant", "llvm_ad_rgb")
    where = doc.get("clrender_device") or doc["cpu"]
    g.text((10, 8), f"clrender / Mitsuba 3 {variant} (> 1: clrender faster)  {doc['spp']} spp, medians of "
                    f"{doc['repeat']}, {where}, {doc['date'][:16]}{trial}", fill="black", font=f)
    for k, (_, label, colour) in enumerate(PLOT_BARS):
        x = 10 + k * 190
        g.rectangle([x, 32, x + 12, 44], fill=colour)
        g.text((x + 16, 31), label, fill="black", font=fs)
    y_end = H - 40
    for q in (1 / 8, 1 / 4, 1 / 2, 1, 2, 4, 8):
        x = x_of(q)
        g.line([x, top - 4, x, y_end], fill=(0, 0, 0) if q == 1 else (215, 215, 215), width=2 if q == 1 else 1)
        g.text((x - 12, y_end + 4), f"{q:g}x" if q >= 1 else f"1/{1 / q:g}x", fill="black", font=fs)
    y = top
    for name in names:
        ratios = doc["results"][name]["ratios"]
        g.text((10, y + (len(PLOT_BARS) * bar) / 2 - 8), name, fill="black", font=f)
        for key, _, colour in PLOT_BARS:
            q = ratios.get(key)
            if q is not None and np.isfinite(q) and q > 0:
                x0, x1 = sorted((x_of(1.0), x_of(q)))
                g.rectangle([x0, y + 1, x1, y + bar - 2], fill=colour)
                g.text((max(x_of(q), x_of(1.0)) + 4, y), f"{q:.2f}x", fill="black", font=fs)
            y += bar
        y += gap
    path.parent.mkdir(parents=True, exist_ok=True)
    img.save(path)
    return path


def _device_name(spec) -> str:
    from clrender.device.context import choose_device

    plat, dev = choose_device(spec)
    return f"{plat.name.strip()} / {dev.name.strip()}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spp", type=int, help=f"default {FULL['spp']}")
    ap.add_argument("--repeat", type=int, help=f"default {FULL['repeat']}")
    ap.add_argument("--reference-spp", type=int, help=f"default {FULL['reference_spp']}")
    ap.add_argument("--res", type=int, help=f"image width and height, default {FULL['res']}")
    ap.add_argument("--quick", action="store_true",
                    help="a trial run: spp 4, repeat 1, reference spp 16, 128x128 (explicit options still win); "
                         "writes ...-quick.json/png")
    ap.add_argument("--no-count-rays", action="store_true", help="skip clrender's ray-counting render")
    ap.add_argument("--only", nargs="*", metavar="TWIN", help="twins to run: " + ", ".join(TWINS))
    ap.add_argument("--device", help="clrender's OpenCL device (index, cpu, gpu or name substring; default PoCL)")
    ap.add_argument("--mitsuba-variant", default="llvm_ad_rgb",
                    help="Mitsuba 3 variant to race (default llvm_ad_rgb; cuda_ad_rgb beside a GPU device)")
    ap.add_argument("--json", help="default: benchmarks/results/vs_mitsuba-<date>.json (the plot: same name, .png)")
    args = ap.parse_args(argv)
    for k, v in (QUICK if args.quick else FULL).items():
        if getattr(args, k) is None:
            setattr(args, k, v)
    unknown = sorted(set(args.only or ()) - set(TWINS))
    if unknown:
        ap.error(f"--only: unknown twin(s) {', '.join(unknown)}; the twins are {', '.join(TWINS)}")
    try:
        import mitsuba  # noqa: F401  (fail early: a benchmark-only dependency)
    except ImportError:
        sys.exit("vs_mitsuba: needs Mitsuba 3 (a benchmark-only dependency): pip install mitsuba==3.9.1")

    say = lambda m: print(f"vs_mitsuba: {m}", file=sys.stderr, flush=True)  # noqa: E731
    load_before = os.getloadavg()
    results = {}
    with tempfile.TemporaryDirectory(prefix="vs-mitsuba-") as tmp:
        for name, d, t in made_twins(tmp, args.only, args.spp, args.res):
            results[name] = bench_twin(t, d, args.spp, args.repeat, args.reference_spp,
                                       say, count_rays=not args.no_count_rays, device=args.device,
                                       variant=args.mitsuba_variant)
    from clrender.bench import git_revision

    doc = {"date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "git_revision": git_revision(),
           "cpu": cpu_name(), "cores": os.cpu_count(), "load_average_before": load_before,
           "load_average": os.getloadavg(), "spp": args.spp, "repeat": args.repeat,
           "reference_spp": args.reference_spp, "res": args.res, "quick": args.quick,
           "mitsuba_variant": args.mitsuba_variant, "clrender_device": _device_name(args.device),
           "results": results}
    suffix = ("-quick" if args.quick else "") + ("" if args.mitsuba_variant == "llvm_ad_rgb" else f"-{args.mitsuba_variant}")
    out = Path(args.json) if args.json else \
        ROOT / "benchmarks" / "results" / f"vs_mitsuba-{dt.date.today()}{suffix}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(doc, indent=1) + "\n")
    png = plot(doc, out.with_suffix(".png"))
    print(f"{'twin':18s} {'renderer':22s} {'samples/s':>10s} {'rays/s':>8s} {'rays/spl':>8s} {'render s':>9s} "
          f"{'relMSE':>9s} {'process s':>9s}")
    for name, r in results.items():
        for k in ("clrender", f"mitsuba {args.mitsuba_variant}"):
            v = r[k]
            rays = "-" if v["rays_per_second"] is None else f"{v['rays_per_second'] / 1e6:.2f}M"
            per = "-" if v["rays_per_sample"] is None else f"{v['rays_per_sample']:.2f}"
            print(f"{name:18s} {k:22s} {v['samples_per_second'] / 1e6:9.2f}M {rays:>8s} {per:>8s} "
                  f"{v['render_seconds']:9.3f} {v['relmse']:9.4f} {v['process_seconds']:9.2f}   mean/ref "
                  + " ".join(f"{x:.3f}" for x in v["image_mean_over_reference"]))
            for key, fr in (v.get("furnace") or {}).items():
                print(f"{'':18s} {'':22s} furnace {key} the sphere: mean {fr['mean']:.4f} +- {fr['stderr']:.4f}"
                      f" (analytic {fr['analytic']:g}, {fr['pixels']} pixels)")
        q = r["ratios"]
        print(f"{name:18s} clrender / mitsuba: samples/s {q['samples_per_second']:.2f}x, time to equal error "
              f"{q['time_to_equal_error']:.2f}x, whole process {q['whole_process']:.2f}x")
    print(f"wrote {out} and {png}")


if __name__ == "__main__":
    main()
