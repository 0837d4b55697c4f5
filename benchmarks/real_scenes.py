"""A development harness over public scene sets: clrender and Mitsuba 3 on the same real scenes, side by side.

    python benchmarks/real_scenes.py FOLDER [FOLDER ...] [--res 96] [--spp 16] [--pairs 1] [--variant scalar_rgb]
                                     [--keep-sampler] [--drop NAME ...] [--only SUBSTRING ...]
                                     [--skip SUBSTRING ...] [--json OUT] [--save DIR]

Not part of the test-suite, and nothing of these sets is ever committed: bring them onto your machine, keep them
outside the work tree and name their folders. Every `*.xml` under a folder whose root is a `<scene>` with a
`<sensor>` (its own or an included file's) is a scene; files in folders named `include` or `fragments` are not. Sets it was written for:
- Benedikt Bitterli's rendering resources (https://benedikt-bitterli.me/resources/), in Mitsuba 3 form
  (`scene_v3.xml`) and in Mitsuba 0.6 form (`scene.xml`, version 0.5/0.6); GitHub copies of the 0.x form exist,
  e.g. jgarciapueyo/mitsuba2-transient-scenes (bathroom, kitchen, staircase, veach-mis, ...).
- Mitsuba 3's own data: mitsuba-renderer/mitsuba-data (docs/scenes, tests/scenes, scenes/cbox), the scenes of
  its documentation and test-suite.
- Course scene sets in Mitsuba format, e.g. BachiLi/lajolla_public (UCSD CSE 272: Crytek Sponza as 37 serialized
  shapes, Veach's MIS scene, matpreview, Cornell boxes, volume tests whose integrators carry the course renderer's
  own `version`: `--drop version`).
- Other renderers' evaluation scenes in Mitsuba form, e.g. PearCoding/Ignis (scenes/evaluation/mitsuba, Mitsuba 2
  files: area, point and environment lights over planes and a room; they look for their meshes in
  scenes/evaluation/meshes and mitsuba/meshes and for their maps in scenes/evaluation/textures, while the
  repository keeps some in scenes/meshes and scenes/textures: put them there).
- Mitsuba's tutorials and exporter tests: mitsuba-renderer/mitsuba-tutorials (scenes/), mitsuba-renderer/mitsuba-blender
  (tests/: scenes without an integrator, see below).
- Users' own scenes: sapo17/BachelorThesis (scenes/: Mitsuba 3 files of a material-optimisation thesis; some give
  Windows paths from the repository's root, which neither renderer finds on Linux), poloclub/revamp (scenes/: files
  whose purchased meshes the repository does not hold: located errors only).
- Research scenes, e.g. VElysianP/mitsuba_scenes (Mitsuba 0.5 files from BSDF and luminaire papers; the ones that
  ask for `path`: layered_kitchen, layered_shoes, leaves_status, shelf_conductor; the others ask for `bdpt` or
  `photonmapper`, which neither Mitsuba 3 nor clrender has).
Bring a set onto your machine from its public repository (a clone, or a `git archive` of it) outside the work tree,
in a folder whose path holds none of the --skip words (a copy named mitsuba2-transient-scenes is skipped whole by
`--skip transient`).

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
- what Mitsuba needed: clrender reads the scene as the user has it (Mitsuba 0.x files and `<path>` included);
  only the film's size, the sample count and the sampler differ from the user's file. Mitsuba reads that same copy
  where it can; where Mitsuba 3.9.1 refuses it, it gets a copy of its own changed as little as it takes, and the
  row says how: `(Mitsuba: lookAt)` (a 0.x `<lookAt>`, which Mitsuba 3 refuses while it upgrades the rest of a
  0.x file itself), `(Mitsuba: -name)` (properties it reports as unreferenced left out: 0.x's `high_quality_edges`,
  `max_smooth_angle`, ...; clrender uses or ignores them with a warning, see README's "Older files"),
  `(Mitsuba: ldrfilm)` (0.x's ldrfilm as an hdrfilm: both compare linear images), `(Mitsuba: sigma_t,albedo)` (a 0.x
  homogeneous medium's `sigmaA`/`sigmaS` as the same medium's `sigma_t`/`albedo`, as clrender reads them; dropped,
  Mitsuba would render its default medium), `(Mitsuba: +path)` (a scene without an `<integrator>`: Mitsuba 3.9.1
  reads it but will not render it, clrender renders Mitsuba's documented default `path`; e.g. mitsuba-blender's
  tests/res/scenes). Where Mitsuba still cannot render a scene, `agrees` says why. Where both refuse a property
  (a 3.x file with 0.x's `high_quality_edges`: Bitterli's Cornell boxes), `--drop NAME` leaves it out of both
  copies, marked `(both: -N)`;
- clrender's warnings (a ptracer rendered by path, 0.x properties ignored, degenerate triangles dropped): the first
  in a line under the row, all of them in the JSON;
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
import logging
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
from clrender.scene.mitsuba_legacy import camel_to_snake  # noqa: E402
from clrender.testing.stats import block_sums  # noqa: E402

BLOCK = 16
PREFIX = "_real_scenes_"
#: above this share of the summed per-pixel variance in one pixel, the noise and block columns are unreliable
#: (bsdf_spheres/test_pointlight_path at 96 px, 64 spp: a point light's sub-pixel highlight, 0.45 to 0.94 of it
#: over 16 pairs; 0.01, 0.09 and 0.17 in bsdf_spheres' constant, envmap and arealight scenes at 96 px, 16 spp)
TOP_PIXEL_WARN = 0.25
#: a block's standard error is at least this share of its mean: the two renderers' float32 sums and constants (a
#: spectrum's RGB) differ at 1e-7 to 1e-5 where a block has no noise (Ignis' emissive-plane.xml: an area light seen
#: head on, 1.0206675 against 1.0206677, read as 20 standard errors of its float noise before this floor)
FLOAT_FLOOR = 1e-4


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


def resized(text, res, keep_sampler, spp=16, outer=None):
    """The scene's XML with its film scaled to `res` pixels along the longer side and (unless keep_sampler) an
    independent sampler; the film's sizes may be numbers or $names with <default>s (of this file, or for an
    included file, of the text `outer` that includes it)."""
    defaults = defaults_of(text) | defaults_of(outer or "")   # the first given (the outer file's) wins

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
    if "<film" not in text:     # Mitsuba's default film (768 x 576), scaled like any other
        text = re.sub(r"(<sensor\b[^>]*?)(/?)>", lambda m: m.group(1) + '><film type="hdrfilm"/>' +
                      ("</sensor>" if m.group(2) else ""), text, count=1)
    for name, val in (("width", nw), ("height", nh)):
        pat = rf'(<integer\s+name="{name}"\s+value=")[^"]+("\s*/>)'
        if re.search(pat, text):
            text = re.sub(pat, rf"\g<1>{val}\g<2>", text)
        else:
            text = re.sub(r"(<film\b[^>]*?)(/?)>", lambda m: m.group(1) + ">" +
                          f'<integer name="{name}" value="{val}"/>' + ("</film>" if m.group(2) else ""), text, count=1)
    # a crop window scaled with the film, kept inside it (mitsuba-blender's film_hdrfilm_crop)
    crop = {k: size(f"crop_{k}") for k in ("offset_x", "offset_y", "width", "height")}
    ox, oy = (min(round((crop[f"offset_{a}"] or 0) * s), n - 1) for a, n in (("x", nw), ("y", nh)))
    cw, ch = (max(1, min(round((crop[k] or 0) * s), n - o)) for k, n, o in (("width", nw, ox), ("height", nh, oy)))
    for name, val in (("offset_x", ox), ("offset_y", oy), ("width", cw), ("height", ch)):
        if crop[name] is not None:
            text = re.sub(rf'(<integer\s+name="crop_{name}"\s+value=")[^"]+("\s*/>)', rf"\g<1>{val}\g<2>", text)
    if not keep_sampler:
        # the independent sampler takes only sample_count and seed: another sampler's own properties (`jitter`,
        # `scramble_seed`, ...) go with it
        def independent(m):
            return re.sub(r'\s*<\w+\s+name="(?!sample_count"|seed")[^"]+"\s+value="[^"]*"\s*/>', "", m.group(0))
        text = re.sub(r'<sampler\b[^>]*?/>|<sampler\b.*?</sampler>', independent, text, flags=re.S)
        text = re.sub(r'<sampler\s+type="[^"]+"', '<sampler type="independent"', text)
    # a sample count given by the caller (Mitsuba's documentation scenes leave $spp to their render script)
    text = re.sub(r'(<integer\s+name="sample_count"\s+value=")\$\w+(")', rf"\g<1>{spp}\g<2>", text)
    return text, (nw, nh)


def resized_includes(text, folder, dirs, args, written, depth=0, outer=None):
    """The scene's text with each <include> of a file that holds a film or a sampler pointed at a resized copy of
    that file written beside it (PREFIX + its name; appended to `written`), recursively: the scene's structure stays
    as the user has it (an included file's <default>s stay in their file, where the first one given wins)."""
    def repl(m):
        name = m.group(2)
        for p in [folder / name] + [d / name for d in dirs]:
            if p.is_file():
                break
        else:
            return m.group(0)
        inner = p.read_text()
        inner = resized_includes(inner, p.parent, dirs, args, written, depth + 1, outer) if depth < 4 else inner
        if "<film" not in inner and "<sampler" not in inner and inner == p.read_text():
            return m.group(0)
        copy = p.parent / f"{PREFIX}{p.name}"
        copy.write_text(resized(inner, args.res, args.keep_sampler, args.spp, outer)[0])
        written.append(copy)
        return m.group(1) + str(Path(name).parent / copy.name) + m.group(3)
    return re.sub(r'(<include\s+filename=")([^"]+)(")', repl, text)


def for_mitsuba(text, error):
    """Mitsuba's copy of the scene, changed as little as it takes to get past `error` (what Mitsuba 3.9.1 said of
    the last copy), and a word for the table saying what was changed; None where nothing here helps. Mitsuba 3
    upgrades 0.x files itself except for <lookAt>, which it refuses; it also refuses 0.x-only properties
    (`high_quality_edges`, `max_smooth_angle`, ...) as unreferenced, and `ldrfilm`, all of which clrender reads."""
    if "unexpected <lookAt>" in error:
        return re.sub(r"<(/?)lookAt\b", r"<\1lookat", text), "lookAt"
    if 'Plugin "ldrfilm" not found' in error:
        return re.sub(r'<film\s+type="ldrfilm"', '<film type="hdrfilm"', text), "ldrfilm"
    if "unreferenced" in error:
        names = set(re.findall(r'^\s*- \w+ "([^"]+)"', error, flags=re.M))
        if {"sigma_a", "sigma_s"} & names:
            converted = media_as_v3(text)
            if converted != text:
                return converted, "sigma_t,albedo"
        if {"density", "method", "step_size"} & names or '"density"' in error:
            converted = re.sub(r'<medium\s+type="heterogeneous".*?</medium>', heterogeneous, text, flags=re.S)
            if converted != text:
                return converted, "density as sigma_t"
        if names:
            def drop(m):
                return "" if camel_to_snake(m.group(1)) in names else m.group(0)
            dropped = re.sub(r'<\w+\s+name="([^"]+)"\s+value="[^"]*"\s*/>', drop, text)
            if dropped != text:     # (subn counts every match, the ones kept too)
                return dropped, "-" + ",".join(sorted(names))
    return None


def media_as_v3(text):
    """0.x homogeneous media given by `sigmaA`/`sigmaS` (which Mitsuba 3.9.1 calls unreferenced) as the same media in
    Mitsuba 3's `sigma_t` = sigma_a + sigma_s and `albedo` = sigma_s / sigma_t, as clrender reads them
    (clrender/scene/mitsuba_legacy.py); left out, Mitsuba would render its default medium instead. Values written as
    numbers (rgb, float, a constant spectrum); any other medium is left as it is."""
    prop = r'<(?:rgb|float|spectrum)\s+name="sigma_?%s"\s+value="([^"]+)"\s*/>'

    def numbers(v):
        x = np.array([float(t) for t in re.split(r"[,\s]+", v.strip())])
        return np.repeat(x, 3) if x.size == 1 else x

    def medium(m):
        body = m.group(0)
        a, s = re.search(prop % "[aA]", body), re.search(prop % "[sS]", body)
        if not (a and s):
            return body
        try:
            sa, ss = numbers(a.group(1)), numbers(s.group(1))
        except ValueError:
            return body
        st = sa + ss
        albedo = np.divide(ss, st, out=np.zeros_like(st), where=st > 0)
        # Mitsuba 3.9.1 refuses an <rgb> above 1 here (an sRGB reflectance): a grey sigma_t as a <float>, a colour
        # one scaled to at most 1 with its largest value moved into `scale`
        peak = float(st.max())
        if np.all(st == peak):
            sigma_t = f'<float name="sigma_t" value="{peak!r}"/>'
        else:
            sigma_t = f'<rgb name="sigma_t" value="{", ".join(map(repr, (st / peak).tolist()))}"/>'
            sc = re.search(r'<float\s+name="scale"\s+value="([^"]+)"\s*/>', body)
            scale = f'<float name="scale" value="{(float(sc.group(1)) * peak) if sc else peak!r}"/>'
            body = body.replace(sc.group(0), scale) if sc else body.replace(a.group(0), a.group(0) + scale)
        return body.replace(s.group(0), "").replace(
            a.group(0), sigma_t + f'<rgb name="albedo" value="{", ".join(map(repr, albedo.tolist()))}"/>')
    return re.sub(r'<medium\s+type="homogeneous".*?</medium>', medium, text, flags=re.S)


def heterogeneous(m):
    """A 0.x heterogeneous medium as clrender reads it (mitsuba_legacy.py): its `density` volume as `sigma_t`, a
    gridvolume spanning its file's bounding box, without `method` and `stepSize`."""
    body = re.sub(r'name="density"', 'name="sigma_t"', m.group(0))
    body = re.sub(r'\s*<(?:string|float)\s+name="(?:method|stepSize|step_size)"\s+value="[^"]*"\s*/>', "", body)
    return re.sub(r'(<volume\s[^>]*type="gridvolume"[^>]*>)', r'\1<boolean name="use_grid_bbox" value="true"/>', body)


def include_dirs(text, folder):
    """The folders a scene's <path value="..."/> elements name (relative ones from the file's folder)."""
    return [folder / m for m in re.findall(r'<path\s+value="([^"]+)"\s*/>', text)]


def first_line(e, names=()):
    """The error's first line, shortened to 160 characters after each (long, short) of `names` is replaced (the
    harness's copies by the scene's name, the scene's folder left out: the reason, not the path, must fit)."""
    s = str(e).strip().splitlines()
    s = s[0] if s else type(e).__name__
    for long, short in names:
        s = s.replace(long, short)
    return s[:160]


def block_stats(a, b):
    """From the renders a (clrender) and b (Mitsuba), two or more each with different seeds: the RMS over blocks of
    each block's mean difference in units of its own standard error (`blocks`), the largest of those (`worst`),
    per-pixel noise ratios (all and the 8 noisiest blocks), the variance of the image mean's difference, the share
    of the summed per-pixel variance that the single noisiest pixel holds, and (for comparison) the RMS block
    difference and worst block in units of the image's RMS block noise (`blocks_pooled`, `worst_pooled`: how they
    were measured before 2026-12-03's third run).

    A block's standard error: one pair of renders gives each block's mean difference two draws per renderer, too
    few to estimate its variance from (a ratio of a normal to so uncertain a scale has heavy tails); its pixels'
    per-pair variances, summed over the block, give its shape with hundreds of degrees of freedom, and one factor
    per renderer, fitted over the whole image (the mean over blocks of their pair variances over those sums), brings in
    the correlation between neighbouring pixels (Mitsuba splats each sample over the filter's footprint, so its
    block means are noisier than independent pixels would make them; clrender's filter importance sampling gives a
    factor near 1). Measured in the image's RMS block noise instead, a block far noisier than the image's average
    (the ceiling around a Cornell box's light) reads as a large difference where it is within its own noise
    (Bitterli's cbox/scene.xml at 128 px, 32 spp: worst 16.9 pooled, 3.4 in its own units)."""
    lum_a, lum_b = ([x[..., :3].mean(axis=2) for x in r] for r in (a, b))
    n = block_sums(lum_a[0], BLOCK)[1]
    ma, mb = (np.stack([block_sums(x, BLOCK)[0] / n for x in lum]) for lum in (lum_a, lum_b))
    diff = ma.mean(axis=0) - mb.mean(axis=0)
    pa, pb = (np.var(np.stack(lum), axis=0, ddof=1) for lum in (lum_a, lum_b))   # per-pixel variance of a render

    def var_of_block_means(m, p):
        """Each block mean's variance (of one render), shaped by its pixels' variances and scaled to the blocks'
        own pair variances over the image."""
        shape = block_sums(p, BLOCK)[0] / n ** 2
        own = m.var(axis=0, ddof=1)
        some = shape > 0
        # the mean of the blocks' ratios, not the ratio of sums, which the few noisiest blocks' pair variances
        # (a couple of degrees of freedom) would decide
        return shape * (own[some] / shape[some]).mean() if some.any() else own

    expected = var_of_block_means(ma, pa) / len(ma) + var_of_block_means(mb, pb) / len(mb)
    # noiseless blocks (a constant emitter seen head on) differ by float rounding, which is no difference
    expected = expected + (FLOAT_FLOOR * np.maximum(np.abs(ma.mean(axis=0)), np.abs(mb.mean(axis=0)))) ** 2
    z = np.divide(diff, np.sqrt(expected), out=np.where(diff == 0, 0.0, np.inf), where=expected > 0)
    blocks, worst = float(np.sqrt((z ** 2).mean())), float(np.abs(z).max())
    pooled = ma.var(axis=0, ddof=1) / len(ma) + mb.var(axis=0, ddof=1) / len(mb)
    scale = np.sqrt(pooled.mean())
    blocks_pooled = float(np.sqrt((diff ** 2).mean()) / scale) if scale > 0 else (0.0 if not diff.any() else np.inf)
    worst_pooled = float(np.abs(diff).max() / scale) if scale > 0 else blocks_pooled
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
    return blocks, worst, noise, noise_worst, var_mean, top_pixel, blocks_pooled, worst_pooled


class Warnings(logging.Handler):
    """clrender's warnings while a scene is read and rendered, for its row (what clrender did differently from the
    file or from Mitsuba: a ptracer rendered by path, 0.x properties ignored, degenerate triangles dropped)."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.messages = []

    def emit(self, record):
        self.messages.append(record.getMessage())


def run_scene(path, args, mi):
    warnings = Warnings()
    logger = logging.getLogger("clrender")
    logger.addHandler(warnings)
    try:
        row = _run_scene(path, args, mi)
    finally:
        logger.removeHandler(warnings)
    tmp = f"{PREFIX}{path.stem}.xml"
    row["clrender_warnings"] = [m.replace(tmp, path.name) for m in warnings.messages]
    return row


def _run_scene(path, args, mi):
    import clrender
    from clrender.renderer import Renderer

    row = {"scene": str(path), "read": None, "mitsuba_read": None, "rendered": None, "agrees": None}
    text = path.read_text()
    written = []        # resized copies of included files that hold the film or the sampler
    text = resized_includes(text, path.parent, include_dirs(text, path.parent), args, written, outer=text)
    if args.drop:   # a property both refuse (Bitterli's 3.x Cornell boxes keep 0.x's high_quality_edges)
        text, n = re.subn(r'<\w+\s+name="(%s)"\s+value="[^"]*"\s*/>' % "|".join(map(re.escape, args.drop)), "", text)
        row["dropped"] = n
    text, (w, h) = resized(text, args.res, args.keep_sampler, args.spp)
    row["size"] = [w, h]
    tmp = path.parent / f"{PREFIX}{path.stem}.xml"
    tmp_mi = path.parent / f"{PREFIX}{path.stem}_mitsuba.xml"
    names = [(str(tmp_mi), path.name), (str(tmp), path.name), (tmp_mi.name, path.name), (tmp.name, path.name),
             (str(path.parent) + os.sep, "")]
    tmp.write_text(text)
    try:
        try:
            scene = clrender.load_scene(tmp)
            row["read"] = "yes"
            row["size"] = [scene.width, scene.height]
        except BaseException as e:     # SceneError and anything else: the harness reports, never stops
            if isinstance(e, KeyboardInterrupt):
                raise
            row["read"] = "no: " + first_line(e, names)
            scene = None
        # Mitsuba reads clrender's copy where it can, else a copy changed as little as it takes (for_mitsuba),
        # and the row says what it needed
        msc, mtext, needed = None, text, []
        for _ in range(6):
            try:
                msc = mi.load_file(str(tmp if mtext is text else tmp_mi))
                row["mitsuba_read"] = "yes"
                break
            except Exception as e:
                row["mitsuba_read"] = "no: " + first_line(e, names)
                fixed = for_mitsuba(mtext, str(e))
                if fixed is None:
                    break
                mtext, what = fixed
                needed.append(what)
                tmp_mi.write_text(mtext)
        if msc is not None and msc.integrator() is None:
            # Mitsuba 3.9.1 reads a scene without an <integrator> but refuses to render it; clrender renders its
            # default, Mitsuba's documented one: Mitsuba's copy gets that `path`
            mtext = re.sub(r"(<scene\b[^>]*>)", r'\1<integrator type="path"/>', mtext, count=1)
            tmp_mi.write_text(mtext)
            msc = mi.load_file(str(tmp_mi))
            needed.append("+path")
        row["mitsuba_needed"] = needed
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
                row["rendered"] = "no: " + first_line(e, names)
        if msc is not None and c is not None:     # (nothing to compare with where clrender stopped)
            t0 = time.perf_counter()
            try:
                m = [np.array(mi.render(msc, spp=args.spp, seed=s), np.float64) for s in range(1, 2 * args.pairs + 1)]
            except Exception as e:      # the harness reports, never stops
                row["agrees"] = "no: Mitsuba did not render it: " + first_line(e, names)
                return row
            tm = time.perf_counter() - t0
            row["mitsuba_seconds"] = tm
            if m[0].ndim == 2:
                m = [x[..., None].repeat(3, axis=2) for x in m]
            if c is not None:
                if m[0].shape[:2] != c[0].shape[:2]:
                    row["agrees"] = f"no: sizes differ ({c[0].shape[1]}x{c[0].shape[0]} vs {m[0].shape[1]}x{m[0].shape[0]})"
                else:
                    mc, mm = np.mean([x.mean() for x in c]), np.mean([x[..., :3].mean() for x in m])
                    blocks, worst, noise, noise_worst, var_mean, top_pixel, bp, wp = block_stats(c, m)
                    ratio = mc / mm if mm > 0 else (1.0 if mc == 0 else np.inf)
                    se = np.sqrt(var_mean) / mm if mm > 0 else 0.0
                    row.update(mean_ratio=float(ratio), mean_ratio_se=float(se), blocks=blocks, worst_block=worst,
                               noise=noise, noise_worst=noise_worst, noise_top_pixel=top_pixel,
                               blocks_pooled=bp, worst_block_pooled=wp,
                               speed=tm / tc if tc else None)
                    if args.save:   # the renders' means, for a look at where they differ
                        args.save.mkdir(parents=True, exist_ok=True)
                        np.savez_compressed(args.save / f"{path.parent.name}_{path.stem}.npz",
                                            clrender=np.mean(c, axis=0)[..., :3], mitsuba=np.mean(m, axis=0)[..., :3],
                                            clrender_var=np.var(np.stack(c)[..., :3], axis=0, ddof=1),
                                            mitsuba_var=np.var(np.stack(m)[..., :3], axis=0, ddof=1))
                    ok = (abs(ratio - 1) <= max(3 * se, 0.01)) and blocks < 1.5
                    row["agrees"] = "yes" if ok else "no"
    finally:
        for f in [tmp, tmp_mi] + written:
            f.unlink(missing_ok=True)
    return row


def fmt(row):
    def g(k, f="{:.3f}"):
        v = row.get(k)
        return "" if v is None else f.format(v)
    name = Path(row["scene"]).parent.name + "/" + Path(row["scene"]).name + \
        (f" (Mitsuba: {', '.join(dict.fromkeys(row['mitsuba_needed']))})" if row.get("mitsuba_needed") else "") + \
        (f" (both: -{row['dropped']})" if row.get("dropped") else "")
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
    ap.add_argument("--drop", nargs="*", default=(), metavar="NAME",
                    help="leave these properties out of both renderers' copies, where both refuse them (rows marked "
                         "'(both: -N)')")
    ap.add_argument("--only", nargs="*", default=(), help="only scenes whose path contains one of these")
    ap.add_argument("--skip", nargs="*", default=(), help="leave out scenes whose path contains one of these")
    ap.add_argument("--pairs", type=int, default=1,
                    help="pairs of renders per renderer (default 1; more where one pixel holds the noise)")
    ap.add_argument("--json", type=Path, help="write the rows and the settings here")
    ap.add_argument("--save", type=Path, metavar="DIR",
                    help="write each compared scene's mean images and per-pixel variances to DIR/<folder>_<name>.npz")
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
        if row["clrender_warnings"]:
            first = row["clrender_warnings"][0].split(": ", 1)[-1]
            more = len(row["clrender_warnings"]) - 1
            print(f"  (clrender warned: {first[:200]}{f'; and {more} more' if more else ''})", flush=True)
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
