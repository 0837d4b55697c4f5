"""A development harness over public scene sets: clrender and Mitsuba 3 on the same real scenes, side by side.

    python benchmarks/real_scenes.py FOLDER [FOLDER ...] [--res 96] [--spp 16] [--pairs 1] [--variant scalar_rgb]
                                     [--keep-sampler] [--upgrade-0x] [--resolve-path] [--drop NAME ...]
                                     [--only SUBSTRING ...]
                                     [--skip SUBSTRING ...] [--json OUT]

Not part of the test-suite, and nothing of these sets is ever committed: bring them onto your machine, keep them
outside the work tree and name their folders. Every `*.xml` under a folder whose root is a `<scene>` with a
`<sensor>` (its own or an included file's) is a scene; files in folders named `include` or `fragments` are not. Sets it was written for:
- Benedikt Bitterli's rendering resources (https://benedikt-bitterli.me/resources/), in Mitsuba 3 form
  (`scene_v3.xml`) and in Mitsuba 0.6 form (`scene.xml`, version 0.5/0.6); GitHub copies of the 0.x form exist,
  e.g. jgarciapueyo/mitsuba2-transient-scenes (bathroom, kitchen, staircase, veach-mis, ...).
- Mitsuba 3's own data: mitsuba-renderer/mitsuba-data (docs/scenes, tests/scenes, scenes/cbox), the scenes of
  its documentation and test-suite.
- Course scene sets in Mitsuba format, e.g. BachiLi/lajolla_public (UCSD CSE 272: Crytek Sponza as 37 serialized
  shapes, Veach's MIS scene, matpreview, Cornell boxes).

Per scene it reports:
- read: whether clrender (and Mitsuba) load it, else the first line of the error;
- rendered: whether clrender renders it;
- agrees: the image mean ratio clrender / Mitsuba with its standard error, and the 16 x 16-block differences
  measured against the noise the two renderers' own render pairs show (`blocks`: RMS over blocks of
  (clrender - Mitsuba) / the RMS it should have from that noise alone; about 1 when they agree, far above 1 where
  an area differs; `worst`: the largest block's difference in those units). Verdict `yes` when the mean agrees
  within 3 standard errors or 1 % and `blocks` is under 1.5;
- noise: clrender's per-pixel noise over Mitsuba's at equal spp (from each one's renders: the RMS of the difference
  of its two, or with --pairs K its per-pixel sample variance over 2K), over the whole image and over the 8
  noisiest 16 x 16 blocks. Where one pixel holds more than TOP_PIXEL_WARN of the summed per-pixel variance (a
  point light's sub-pixel highlight on a near-specular surface), a line under the row says so: noise and blocks
  then rest on that pixel's few samples and swing from pair to pair (bsdf_spheres/test_pointlight_path at 96 px,
  64 spp, over 16 pairs of seeds: noise 0.17 to 2.79, blocks 0.13 to 4.1, for the same renderers); rerun it
  with more --pairs;
- with --upgrade-0x, Mitsuba 0.x scenes (which clrender refuses, and whose <lookAt> Mitsuba 3 refuses) are read
  by both from a textual upgrade to 3.x names without the 0.x-only properties (DROPPED_0X), marked (0.x); with
  --resolve-path, files found through a scene's <path> folders get absolute names and the <path>s go, marked (path);
  --drop NAME... leaves those properties out (e.g. a pinhole's focus_distance, which Mitsuba ignores), marked (-N);
- speed: Mitsuba's render seconds / clrender's (above 1: clrender is faster), render only (no loading, no
  kernel build), both on this machine's CPU.

Each scene is rendered at --res pixels along its longer side (the film's width and height scaled, aspect kept)
and --spp samples, twice by each renderer (seeds 1 and 2; 2K times with --pairs K, seeds 1 to 2K), from a copy
of its XML written beside it (`_real_scenes_<name>.xml`, removed afterwards) so that relative paths still resolve.
Unless --keep-sampler, the copy's sampler is `independent` in both: Mitsuba 3.9.1's `ldsampler` overestimates once Russian roulette starts
(about +0.8 % on Crytek Sponza and on a closed furnace room; tests/test_closed_room.py), so it is no reference.
Mitsuba is a development-only dependency: `pip install mitsuba`; `--variant llvm_ad_rgb` needs libLLVM >= 16
(DRJIT_LIBLLVM_PATH, as benchmarks/vs_mitsuba.py sets it).
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import re
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
if "DRJIT_LIBLLVM_PATH" not in os.environ and Path(LLVM).is_file():
    os.environ["DRJIT_LIBLLVM_PATH"] = LLVM
sys.path.insert(0, str(ROOT))
from clrender.testing.stats import block_sums  # noqa: E402

BLOCK = 16
#: Mitsuba 0.x properties that Mitsuba 3 has no counterpart for (hdrfilm's edge filtering and banner, the
#: sampler's dimension count, 0.x's normal smoothing of serialized meshes, which leaves the file's normals)
DROPPED_0X = ("high_quality_edges", "banner", "dimension", "max_smooth_angle", "attach_log")
PREFIX = "_real_scenes_"
#: above this share of the summed per-pixel variance in one pixel, the noise and block columns are unreliable
#: (bsdf_spheres/test_pointlight_path at 96 px, 64 spp: a point light's sub-pixel highlight, 0.45 to 0.94 of it
#: over 16 pairs; 0.01, 0.09 and 0.17 in bsdf_spheres' constant, envmap and arealight scenes at 96 px, 16 spp)
TOP_PIXEL_WARN = 0.25


def find_scenes(folders, only=(), skip=()):
    """Every scene file under the folders: XML whose root is <scene> and which has a <sensor> somewhere."""
    found = []
    for folder in folders:
        for path in sorted(Path(folder).rglob("*.xml")):
            if path.name.startswith(PREFIX) or (only and not any(s in str(path) for s in only)) or \
                    any(s in str(path) for s in skip):
                continue
            try:
                root = ET.parse(path).getroot()
            except (ET.ParseError, OSError):
                continue
            if root.tag == "scene" and not {"include", "fragments"} & set(path.relative_to(folder).parts[:-1]) \
                    and has_sensor(root, path.parent):
                found.append(path)
    return found


def has_sensor(root, folder, depth=0):
    """Whether the scene (or a file it includes) has a <sensor>."""
    if root.find(".//sensor") is not None:
        return True
    for inc in root.iter("include"):
        try:
            sub = ET.parse(folder / inc.get("filename", "")).getroot()
        except (ET.ParseError, OSError):
            continue
        if depth < 4 and has_sensor(sub, (folder / inc.get("filename", "")).parent, depth + 1):
            return True
    return False


def defaults_of(text):
    return dict(re.findall(r'<default\s+name="([^"]+)"\s+value="([^"]*)"', text))


def resized(text, res, keep_sampler, spp=16):
    """The scene's XML with its film scaled to `res` pixels along the longer side and (unless keep_sampler) an
    independent sampler; the film's sizes may be numbers or $names with <default>s."""
    defaults = defaults_of(text)

    def size(name):
        m = re.search(rf'<integer\s+name="{name}"\s+value="([^"]+)"\s*/>', text)
        if not m:
            return None
        v = m.group(1)
        return int(defaults.get(v[1:], 0)) if v.startswith("$") else int(v)

    w, h = size("width"), size("height")
    w, h = w or 768, h or 576       # Mitsuba's hdrfilm defaults
    s = res / max(w, h)
    nw, nh = max(1, round(w * s)), max(1, round(h * s))
    for name, val in (("width", nw), ("height", nh)):
        pat = rf'(<integer\s+name="{name}"\s+value=")[^"]+("\s*/>)'
        if re.search(pat, text):
            text = re.sub(pat, rf"\g<1>{val}\g<2>", text)
        else:
            text = re.sub(r"(<film\b[^>]*?)(/?)>", lambda m: m.group(1) + ">" +
                          f'<integer name="{name}" value="{val}"/>' + ("</film>" if m.group(2) else ""), text, count=1)
    if not keep_sampler:
        text = re.sub(r'<sampler\s+type="[^"]+"', '<sampler type="independent"', text)
    # a sample count given by the caller (Mitsuba's documentation scenes leave $spp to their render script)
    text = re.sub(r'(<integer\s+name="sample_count"\s+value=")\$\w+(")', rf"\g<1>{spp}\g<2>", text)
    return text, (nw, nh)


def inline_includes(text, folder, depth=0):
    """<include filename="..."/> replaced by the included file's children (for films defined in an include)."""
    def repl(m):
        p = folder / m.group(1)
        try:
            inner = p.read_text()
        except OSError:
            return m.group(0)
        inner = re.sub(r"<\?xml[^>]*\?>", "", inner)
        inner = re.sub(r"^\s*(<!--.*?-->\s*)*<scene[^>]*>", "", inner, flags=re.S)
        inner = inner[:inner.rfind("</scene>")] if "</scene>" in inner else inner
        return inline_includes(inner, p.parent, depth + 1) if depth < 4 else inner
    return re.sub(r'<include\s+filename="([^"]+)"\s*/>', repl, text)


def upgraded(text):
    """A Mitsuba 0.x scene's text in 3.x form, for both renderers (--upgrade-0x): version 3.0.0, camelCase property
    names in snake_case (intIOR -> int_ior, toWorld -> to_world), <lookAt> as <lookat>, and the 0.x-only properties
    that Mitsuba 3 refuses (DROPPED_0X) left out. Textual, for comparison runs only; clrender's own reader refuses
    0.x files and says so."""
    m = re.search(r'<scene\s+version="(0\.[^"]*)"', text)
    if not m:
        return text, False
    text = text.replace(m.group(0), '<scene version="3.0.0"')
    text = re.sub(r'(\bname=")([A-Za-z0-9_]+)(")', lambda q: q.group(1) + re.sub(
        r"([a-z0-9])([A-Z])", r"\1_\2", q.group(2)).lower() + q.group(3), text)
    text = re.sub(r'<\w+\s+name="(%s)"\s+value="[^"]*"\s*/>' % "|".join(DROPPED_0X), "", text)
    return re.sub(r"<(/?)lookAt\b", r"<\1lookat", text), True


def resolved_paths(text, folder, dirs=None):
    """The scene's text with its <path value="..."/> elements removed and every relative filename that is not found
    beside the scene made absolute from the first of those folders that holds it (--resolve-path: for comparison
    runs only, like --upgrade-0x)."""
    dirs = (dirs or []) + [folder / m for m in re.findall(r'<path\s+value="([^"]+)"\s*/>', text)]
    if not dirs:
        return text, False
    text = re.sub(r'<path\s+value="[^"]+"\s*/>', "", text)

    def repl(m):
        f = m.group(2)
        if os.path.isabs(f) or f.startswith("$") or (folder / f).exists():
            return m.group(0)
        for d in dirs:
            if (d / f).exists():
                return m.group(1) + str((d / f).resolve()) + m.group(3)
        return m.group(0)
    return re.sub(r'((?:name="filename"\s+value="|<include\s+filename="))([^"]+)(")', repl, text), True


def first_line(e):
    s = str(e).strip().splitlines()
    return (s[0] if s else type(e).__name__)[:160]


def block_stats(a, b):
    """From the renders a (clrender) and b (Mitsuba), two or more each with different seeds: the RMS block
    difference of their means over its expected RMS, the worst block in those units, per-pixel noise ratios (all
    and the 8 noisiest blocks), the variance of the image mean's difference, and the share of the summed
    per-pixel variance that the single noisiest pixel holds. Variances are the renders' sample variances, so
    one pair each gives the pair-difference formulas ((x1 - x2)^2 / 4 for the variance of a pair's mean)."""
    lum_a, lum_b = ([x[..., :3].mean(axis=2) for x in r] for r in (a, b))
    n = block_sums(lum_a[0], BLOCK)[1]
    ma, mb = (np.stack([block_sums(x, BLOCK)[0] / n for x in lum]) for lum in (lum_a, lum_b))
    diff = ma.mean(axis=0) - mb.mean(axis=0)
    expected = ma.var(axis=0, ddof=1) / len(ma) + mb.var(axis=0, ddof=1) / len(mb)  # var of the means' difference
    scale = np.sqrt(expected.mean())
    blocks = float(np.sqrt((diff ** 2).mean()) / scale) if scale > 0 else (0.0 if not diff.any() else np.inf)
    worst = float(np.abs(diff).max() / scale) if scale > 0 else blocks
    pa, pb = (np.var(np.stack(lum), axis=0, ddof=1) for lum in (lum_a, lum_b))   # per-pixel variance of a render
    na, nb = block_sums(pa, BLOCK)[0], block_sums(pb, BLOCK)[0]
    noise = float(np.sqrt(na.sum() / max(nb.sum(), 1e-30)))
    top = np.argsort(nb.ravel())[-8:]
    noise_worst = float(np.sqrt(na.ravel()[top].sum() / max(nb.ravel()[top].sum(), 1e-30)))
    # the image mean's standard error from the blocks (blocks are nearly independent; pixels are not in
    # Mitsuba's splatted films)
    w = n / n.sum()
    var_mean = float(((w ** 2) * expected).sum())
    total = pa + pb
    top_pixel = float(total.max() / total.sum()) if total.sum() > 0 else 0.0
    return blocks, worst, noise, noise_worst, var_mean, top_pixel


def run_scene(path, args, mi):
    import clrender
    from clrender.renderer import Renderer

    row = {"scene": str(path), "read": None, "mitsuba_read": None, "rendered": None, "agrees": None}
    text = path.read_text()
    dirs = [path.parent / m for m in re.findall(r'<path\s+value="([^"]+)"\s*/>', text)]
    if args.resolve_path:
        text, row["paths_resolved"] = resolved_paths(text, path.parent)
    if "<film" not in text or (args.resolve_path and dirs):   # included files' names go through the <path>s too
        text = inline_includes(text, path.parent)
        if args.resolve_path:       # the included files' names, through the main file's <path>s
            text = resolved_paths(text, path.parent, dirs)[0]
    if args.upgrade_0x:
        text, row["upgraded"] = upgraded(text)
    if args.drop:
        text, n = re.subn(r'<\w+\s+name="(%s)"\s+value="[^"]*"\s*/>' % "|".join(map(re.escape, args.drop)), "", text)
        row["dropped"] = n
    text, (w, h) = resized(text, args.res, args.keep_sampler, args.spp)
    row["size"] = [w, h]
    tmp = path.parent / f"{PREFIX}{path.stem}.xml"
    tmp.write_text(text)
    try:
        try:
            scene = clrender.load_scene(tmp)
            row["read"] = "yes"
        except BaseException as e:     # SceneError and anything else: the harness reports, never stops
            if isinstance(e, KeyboardInterrupt):
                raise
            row["read"] = "no: " + first_line(e).replace(str(tmp), path.name).replace(tmp.name, path.name)
            scene = None
        try:
            msc = mi.load_file(str(tmp))
            row["mitsuba_read"] = "yes"
        except Exception as e:
            row["mitsuba_read"] = "no: " + first_line(e)
            msc = None
        c, tc = None, None
        if scene is not None:
            try:
                r = Renderer(scene)
                films = [r.render(spp=args.spp, seed=s) for s in range(1, 2 * args.pairs + 1)]
                c = [f.image.astype(np.float64) for f in films]
                tc = sum(f.metadata["render_seconds"] for f in films)
                row["rendered"] = "yes"
                row["clrender_seconds"] = tc
            except BaseException as e:
                if isinstance(e, KeyboardInterrupt):
                    raise
                row["rendered"] = "no: " + first_line(e)
        if msc is not None:
            t0 = time.perf_counter()
            m = [np.array(mi.render(msc, spp=args.spp, seed=s), np.float64) for s in range(1, 2 * args.pairs + 1)]
            tm = time.perf_counter() - t0
            row["mitsuba_seconds"] = tm
            if m[0].ndim == 2:
                m = [x[..., None].repeat(3, axis=2) for x in m]
            if c is not None:
                if m[0].shape[:2] != c[0].shape[:2]:
                    row["agrees"] = f"no: sizes differ ({c[0].shape[1]}x{c[0].shape[0]} vs {m[0].shape[1]}x{m[0].shape[0]})"
                else:
                    mc, mm = np.mean([x.mean() for x in c]), np.mean([x[..., :3].mean() for x in m])
                    blocks, worst, noise, noise_worst, var_mean, top_pixel = block_stats(c, m)
                    ratio = mc / mm if mm > 0 else (1.0 if mc == 0 else np.inf)
                    se = np.sqrt(var_mean) / mm if mm > 0 else 0.0
                    row.update(mean_ratio=float(ratio), mean_ratio_se=float(se), blocks=blocks, worst_block=worst,
                               noise=noise, noise_worst=noise_worst, noise_top_pixel=top_pixel,
                               speed=tm / tc if tc else None)
                    ok = (abs(ratio - 1) <= max(3 * se, 0.01)) and blocks < 1.5
                    row["agrees"] = "yes" if ok else "no"
    finally:
        tmp.unlink(missing_ok=True)
    return row


def fmt(row):
    def g(k, f="{:.3f}"):
        v = row.get(k)
        return "" if v is None else f.format(v)
    name = Path(row["scene"]).parent.name + "/" + Path(row["scene"]).name + (" (0.x)" if row.get("upgraded") else "") + \
        (" (path)" if row.get("paths_resolved") else "") + (f" (-{row['dropped']})" if row.get("dropped") else "")
    mean = "" if "mean_ratio" not in row else f"{row['mean_ratio']:.3f} ± {row['mean_ratio_se']:.3f}"
    noise = "" if "noise" not in row else f"{row['noise']:.2f} / {row['noise_worst']:.2f}"
    blocks = "" if "blocks" not in row else f"{row['blocks']:.2f} ({row['worst_block']:.1f})"
    return (f"| {name} | {row['read']} | {row['mitsuba_read']} | {row['rendered'] or ''} | {row['agrees'] or ''} | "
            f"{mean} | {blocks} | {noise} | {g('speed', '{:.2f}')} |")


HEADER = ("| scene | read | Mitsuba reads | rendered | agrees | mean ratio | blocks (worst) | noise (worst 8) | speed |\n"
          "|---|---|---|---|---|---|---|---|---|")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folders", nargs="+", type=Path)
    ap.add_argument("--res", type=int, default=96, help="pixels along the longer side (default 96)")
    ap.add_argument("--spp", type=int, default=16, help="samples per pixel of each render (default 16)")
    ap.add_argument("--variant", default="scalar_rgb", help="Mitsuba variant (default scalar_rgb)")
    ap.add_argument("--keep-sampler", action="store_true", help="keep each scene's sampler (default: independent)")
    ap.add_argument("--upgrade-0x", action="store_true",
                    help="render Mitsuba 0.x scenes from a textual 3.x upgrade (both renderers; marked '(0.x)')")
    ap.add_argument("--resolve-path", action="store_true",
                    help="resolve <path> folders textually for both renderers (marked '(path)')")
    ap.add_argument("--drop", nargs="*", default=(), metavar="NAME",
                    help="leave these properties out of every copy, for both renderers (rows marked '(-N)')")
    ap.add_argument("--only", nargs="*", default=(), help="only scenes whose path contains one of these")
    ap.add_argument("--skip", nargs="*", default=(), help="leave out scenes whose path contains one of these")
    ap.add_argument("--pairs", type=int, default=1,
                    help="pairs of renders per renderer (default 1; more where one pixel holds the noise)")
    ap.add_argument("--json", type=Path, help="write the rows and the settings here")
    args = ap.parse_args(argv)
    if args.pairs < 1:
        ap.error(f"--pairs must be at least 1, got {args.pairs}")
    import mitsuba as mi
    mi.set_variant(args.variant)
    mi.set_log_level(mi.LogLevel.Error)
    scenes = find_scenes(args.folders, args.only, args.skip)
    try:
        commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                                text=True).stdout.strip()
    except OSError:
        commit = ""
    print(f"{dt.date.today()}  commit {commit}  Mitsuba {mi.__version__} {args.variant}  "
          f"{args.res} px, {args.spp} spp x {2 * args.pairs} each, {len(scenes)} scenes", flush=True)
    print(HEADER, flush=True)
    rows = []
    for path in scenes:
        row = run_scene(path, args, mi)
        rows.append(row)
        print(fmt(row), flush=True)
        if row.get("noise_top_pixel", 0) > TOP_PIXEL_WARN:
            print(f"  ({Path(row['scene']).name}: one pixel holds {100 * row['noise_top_pixel']:.0f} % of the "
                  f"per-pixel variance, so its noise and blocks rest on that pixel's few samples and swing "
                  f"from seed to seed; more --pairs steady them)", flush=True)
    if args.json:
        args.json.write_text(json.dumps({"date": str(dt.date.today()), "commit": commit, "settings": vars(args) | {
            "folders": [str(f) for f in args.folders], "json": str(args.json)}, "rows": rows}, indent=1,
            default=str))


if __name__ == "__main__":
    main()
