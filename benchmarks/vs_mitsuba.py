"""clrender and Mitsuba 3 side by side: the same twin scenes, rendered by both in one run, interleaved.

    python benchmarks/vs_mitsuba.py [--spp 64] [--repeat 5] [--reference-spp 1024] [--json OUT] [--only NAME ...]

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

Figures per twin and renderer (medians of --repeat interleaved renders after a warm-up): render seconds and
samples/s (render only, in process), whole-process seconds (a fresh `clrender render` / `python -c` Mitsuba
process: start, load, build, render, write), relMSE at --spp and the time to equal error (seconds x relMSE:
the render time at which each reaches the other's error, assuming error ~ 1/time). Written to
benchmarks/results/vs_mitsuba-<date>.json and printed as a table.
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


def twin_cornell(d: Path, spp: int, with_spheres: bool = True) -> dict:
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
    return dict(name="cornell_spheres" if with_spheres else "cornell", shapes=shapes, camera=CAMERA, spp=spp)


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


# -------------------------------------------------------------------------------------------------- renderers
class Clrender:
    name = "clrender"

    def __init__(self, xml: Path):
        import clrender
        from clrender.renderer import Renderer

        self.xml = xml
        self.renderer = Renderer(clrender.load_scene(xml))
        self.renderer.render(spp=1)  # build + first launch

    def render(self, spp: int, seed: int):
        film = self.renderer.render(spp=spp, seed=seed)
        return film.image.astype(np.float64), film.stats.seconds

    def process_cmd(self, spp: int, out: Path):
        return [sys.executable, "-m", "clrender.cli", "render", str(self.xml), "--spp", str(spp), "-q", "-o", str(out)]


class Mitsuba:
    name = "mitsuba llvm_ad_rgb"

    def __init__(self, xml: Path):
        import mitsuba as mi

        mi.set_variant("llvm_ad_rgb")
        self.mi, self.xml = mi, xml
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
        code = ("import mitsuba as mi; mi.set_variant('llvm_ad_rgb'); "
                f"s = mi.load_file({str(self.xml)!r}); img = mi.render(s, spp={spp}); "
                f"mi.util.write_bitmap({str(out)!r}, img)")
        return [sys.executable, "-c", code]


def relmse(img, ref):
    return float(np.mean((img - ref) ** 2 / (ref * ref + 1e-2)))


def bench_twin(t: dict, d: Path, spp: int, repeat: int, ref_spp: int, say) -> dict:
    (d / "clrender.xml").write_text(scene_xml(t, "nori"))
    (d / "mitsuba.xml").write_text(scene_xml(t, "mitsuba"))
    rs = [Clrender(d / "clrender.xml"), Mitsuba(d / "mitsuba.xml")]
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
                     "all": v}
    a, b = out["clrender"], out["mitsuba llvm_ad_rgb"]
    out["ratios"] = {"samples_per_second": a["samples_per_second"] / b["samples_per_second"],
                     "time_to_equal_error": b["time_x_error"] / a["time_x_error"],
                     "whole_process": b["process_seconds"] / a["process_seconds"]}
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--reference-spp", type=int, default=1024)
    ap.add_argument("--only", nargs="*")
    ap.add_argument("--json", help="default: benchmarks/results/vs_mitsuba-<date>.json")
    args = ap.parse_args(argv)
    import mitsuba  # noqa: F401  (fail early: a benchmark-only dependency)

    say = lambda m: print(f"vs_mitsuba: {m}", file=sys.stderr, flush=True)  # noqa: E731
    twins = {"cornell_spheres": lambda d: twin_cornell(d, args.spp),
             "cornell": lambda d: twin_cornell(d, args.spp, with_spheres=False)}
    results = {}
    with tempfile.TemporaryDirectory(prefix="vs-mitsuba-") as tmp:
        for name, make in twins.items():
            if args.only and name not in args.only:
                continue
            d = Path(tmp) / name
            results[name] = bench_twin(make(d), d, args.spp, args.repeat, args.reference_spp, say)
    from clrender.bench import git_revision

    doc = {"date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"), "git_revision": git_revision(),
           "cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
           "load_average": os.getloadavg(), "spp": args.spp, "repeat": args.repeat,
           "reference_spp": args.reference_spp, "results": results}
    out = Path(args.json) if args.json else ROOT / "benchmarks" / "results" / f"vs_mitsuba-{dt.date.today()}.json"
    out.write_text(json.dumps(doc, indent=1) + "\n")
    print(f"{'twin':18s} {'renderer':22s} {'samples/s':>10s} {'render s':>9s} {'relMSE':>9s} {'process s':>9s}")
    for name, r in results.items():
        for k in ("clrender", "mitsuba llvm_ad_rgb"):
            v = r[k]
            print(f"{name:18s} {k:22s} {v['samples_per_second'] / 1e6:9.2f}M {v['render_seconds']:9.3f} "
                  f"{v['relmse']:9.4f} {v['process_seconds']:9.2f}   mean/ref "
                  + " ".join(f"{x:.3f}" for x in v["image_mean_over_reference"]))
        q = r["ratios"]
        print(f"{name:18s} clrender / mitsuba: samples/s {q['samples_per_second']:.2f}x, time to equal error "
              f"{q['time_to_equal_error']:.2f}x, whole process {q['whole_process']:.2f}x")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
