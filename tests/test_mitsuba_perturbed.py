"""Mitsuba 3's normalmap and bumpmap on the device (kernels/bsdfs/{normalmap,bumpmap,perturb}.h):

- values against Mitsuba 3.9.1 itself at fixed surface points (uv, shading frame, geometric normal, dp/du, dp/dv)
  and direction pairs: tests/mitsuba/bsdf_values/perturbed.json, written by make_perturbed_values.py in that
  folder (Mitsuba is not needed to run this);
- a flat normal map (0.5, 0.5, 1) and a constant height give exactly the child's values;
- chi-square of the wrapped sampling routine against its own pdf for tilted normals, and weight == f cos / pdf;
- the bitmap's uv gradient (bumpmap's slope) on the device against the host's (clrender/textures/bitmap.py, itself
  checked against Mitsuba's eval_1_grad when the refs were made);
- the scene errors (a texture without a gradient, missing children, nesting deeper than the dispatch has).
"""
import json
from pathlib import Path

import numpy as np
import pytest

from clrender import plugins  # noqa: F401  (registers the plugins)
from clrender.errors import SceneError
from clrender.scene.registry import create
from clrender.scene.spec import PluginSpec
from clrender.scene.transform import Transform
from clrender.testing.chi2 import bin_directions, chi2_test, expected_from_grid, refined_direction_grid
from clrender.testing.kernels import bsdf_pdf_eval_batch, bsdf_sample_batch, pack_rows
from clrender.testing.mitsuba_dict import spec_from_dict
from clrender.textures.texture import TextureTable

VALUES = Path(__file__).resolve().parent / "mitsuba" / "bsdf_values"
DATA = json.loads((VALUES / "perturbed.json").read_text())


def _files_and_to_uv(props, key, value) -> bool:
    if key == "filename":
        props.add(key, "string", str(VALUES / value))
    elif key == "to_uv":
        props.add(key, "transform", Transform(DATA["to_uv"][value]))
    else:
        return False
    return True


def spec(d: dict, tag: str = "bsdf") -> PluginSpec:
    """The plugin spec of a Mitsuba-style dict (nested textures by their key, files in VALUES)."""
    return spec_from_dict(d, tag, special=_files_and_to_uv)


def rows_of(d):
    rows = pack_rows(create(spec(d)))
    return rows, rows.textures


def beckmann_visible(d):
    """Mitsuba samples Beckmann visible normals in `d` somewhere (clrender: D cos, another valid density)."""
    if d.get("type") in ("roughplastic", "roughconductor", "roughdielectric") and \
            d.get("distribution", "beckmann") == "beckmann" and d.get("sample_visible", True):
        return True
    return any(beckmann_visible(v) for v in d.values() if isinstance(v, dict))


@pytest.mark.parametrize("name", sorted(DATA["cases"]))
def test_eval_and_pdf_match_mitsuba(ctx, queue, name):
    case = DATA["cases"][name]
    rows, tex = rows_of(case["dict"])
    pts = DATA["points"]
    wo = np.concatenate([p["wo"] for p in pts])
    n = len(pts[0]["wo"])
    wi = np.repeat([p["wi"] for p in pts], n, axis=0)
    uv = np.repeat([p["uv"] for p in pts], n, axis=0)
    geo = np.repeat([p["geometry"] for p in pts], n, axis=0)
    pdf, f = bsdf_pdf_eval_batch(ctx, queue, rows, wi, wo, uv=uv, textures=tex, geometry=geo)
    ref = np.concatenate([p["eval"] for p in case["points"]])
    ref_pdf = np.concatenate([p["pdf"] for p in case["points"]])
    got = f * np.abs(wo[:, 2:3])
    assert np.count_nonzero(ref.any(axis=1)) > len(ref) // 4, "the reference must reflect somewhere"
    # float32 against Mitsuba's float32; roughplastic's tabulated transmittance differs by up to 1 % (see
    # test_mitsuba_coated.py)
    rough = "roughplastic" in json.dumps(case["dict"])
    rtol = 1e-2 if rough else 3e-3
    close = np.abs(got - ref) <= 2e-5 + rtol * np.abs(ref)
    bad = np.nonzero(~close.all(axis=1))[0]
    assert len(bad) == 0, f"{name}: eval differs from Mitsuba's at pairs {bad.tolist()}: " \
                          f"{got[bad][:4].tolist()} vs {ref[bad][:4].tolist()}"
    if not beckmann_visible(case["dict"]):
        close = np.abs(pdf - ref_pdf) <= 2e-5 + (4e-2 if rough else 3e-3) * np.abs(ref_pdf)
        bad = np.nonzero(~close)[0]
        assert len(bad) == 0, f"{name}: pdf differs from Mitsuba's at pairs {bad.tolist()}: " \
                              f"{pdf[bad][:4].tolist()} vs {ref_pdf[bad][:4].tolist()}"


# ---------------------------------------------------------------------------------- the height's gradient
GRAD_SRC = r"""
#include "texture.h"
#include "textures/bitmap.h"
__kernel void grad(__global const Texture* textures, uint row, __global const float2* uv, __global float2* out) {
    uint i = get_global_id(0);
    out[i] = bitmap_grad(textures + row, uv[i]);
}
"""


@pytest.mark.parametrize("name", sorted(DATA["gradients"]))
def test_bitmap_gradient_is_mitsubas(ctx, queue, name):
    """bumpmap's slope: the bitmap's uv gradient on the device (bitmap_grad) and on the host (Bitmap.eval_grad) as
    Mitsuba's eval_1_grad gives it (of the luminance, through to_uv, every wrap mode; none for `nearest`)."""
    import pyopencl as cl

    from clrender.device.program import build_program

    case = DATA["gradients"][name]
    tex = create(spec(case["dict"], "texture")).float_view()
    uv, ref = np.array(case["uv"]), np.array(case["grad"])
    np.testing.assert_allclose(tex.eval_grad(uv), ref, rtol=1e-4, atol=1e-4 * np.abs(ref).max())
    table = TextureTable()
    row = table.add(tex)
    mf = cl.mem_flags
    d_tex = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=table.array())
    d_uv = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=uv.astype(np.float32))
    out = np.empty((len(uv), 2), np.float32)
    d_out = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
    cl.Kernel(build_program(ctx, GRAD_SRC), "grad")(queue, (len(uv),), None, d_tex, np.uint32(row), d_uv, d_out)
    cl.enqueue_copy(queue, out, d_out)
    queue.finish()
    np.testing.assert_allclose(out, ref, rtol=1e-3, atol=1e-3 * np.abs(ref).max())
    if name == "nearest":
        assert not ref.any()
    else:
        assert np.abs(ref).max() > 0.5


# ------------------------------------------------------------------------- an unperturbed frame is the child's
def _pairs(n=400, seed=3):
    rng = np.random.default_rng(seed)
    wi = rng.normal(size=(n, 3))
    wi[:, 2] = np.abs(wi[:, 2]) * np.where(np.arange(n) % 9 == 0, -1, 1)    # some from the back
    wo = rng.normal(size=(n, 3))
    return wi / np.linalg.norm(wi, axis=1, keepdims=True), wo / np.linalg.norm(wo, axis=1, keepdims=True)


FLAT_CHILDREN = {
    "diffuse": {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.2, 0.6, 0.4]}},
    "aniso": {"type": "roughconductor", "distribution": "ggx", "alpha_u": 0.05, "alpha_v": 0.3},
    "roughplastic": {"type": "roughplastic", "alpha": 0.2},
    "roughdielectric": {"type": "roughdielectric", "alpha": 0.3},
    "dielectric": {"type": "dielectric"},
    "blend": {"type": "blendbsdf", "weight": 0.3, "a": {"type": "conductor"}, "b": {"type": "diffuse"}},
}


def _flat_wrappers(child, tmp_path):
    # a constant height: a bitmap of one grey (its slope is 0 everywhere); the normal map: (0.5, 0.5, 1) itself
    from clrender.png import encode_png

    (tmp_path / "flat.png").write_bytes(encode_png(np.full((3, 4, 3), 77, np.uint8)))
    yield "normalmap", {"type": "normalmap", "normalmap": {"type": "rgb", "value": [0.5, 0.5, 1.0]}, "bsdf": child}
    yield "bumpmap", {"type": "bumpmap", "scale": 3.0, "h": {"type": "bitmap", "filename": str(tmp_path / "flat.png")},
                      "bsdf": child}
    yield "bumpmap-nearest", {"type": "bumpmap", "scale": 3.0,
                              "h": {"type": "bitmap", "filename": str(VALUES / "perturbed_height.png"),
                                    "filter_type": "nearest"}, "bsdf": child}


@pytest.mark.parametrize("child", sorted(FLAT_CHILDREN))
def test_an_unperturbed_wrapper_is_its_child(ctx, queue, child, tmp_path):
    """A flat normal map and a bump map without slope leave the frame as it is: the child's eval, pdf and samples
    exactly (the default query geometry: dp/du along the shading frame's first axis)."""
    wi, wo = _pairs()
    uv = np.random.default_rng(5).uniform(0, 1, (len(wi), 2))
    crows, ctex = rows_of(FLAT_CHILDREN[child])
    cpdf, cf = bsdf_pdf_eval_batch(ctx, queue, crows, wi, wo, uv=uv, textures=ctex)
    cs = bsdf_sample_batch(ctx, queue, crows, wi, len(wi), seed=11, uv=uv, textures=ctex)
    assert np.count_nonzero(cf.any(axis=1)) > 50 or np.count_nonzero(cs.weight.any(axis=1)) > 50
    for name, d in _flat_wrappers(FLAT_CHILDREN[child], tmp_path):
        rows, tex = rows_of(d)
        pdf, f = bsdf_pdf_eval_batch(ctx, queue, rows, wi, wo, uv=uv, textures=tex)
        np.testing.assert_array_equal(pdf, cpdf, err_msg=name)
        np.testing.assert_array_equal(f, cf, err_msg=name)
        s = bsdf_sample_batch(ctx, queue, rows, wi, len(wi), seed=11, uv=uv, textures=tex)
        for field in ("wo", "weight", "pdf", "measure", "eta", "f"):
            np.testing.assert_array_equal(getattr(s, field), getattr(cs, field), err_msg=f"{name}: {field}")


# ---------------------------------------------------------------------------------- sampling (chi-square)
RES, SUB = 10, 8
N_SAMPLES = 400_000
TILTED = {   # name: (wrapper dict, wi, uv, the normal the wrapper should reflect about, roughly (for the grid))
    "normalmap-roughconductor": ({"type": "normalmap", "normalmap": {"type": "rgb", "value": [0.75, 0.4, 0.85]},
                                  "bsdf": {"type": "roughconductor", "alpha": 0.25, "distribution": "ggx"}},
                                 [0.3, -0.2, 0.9], (0.5, 0.5), 0.25),
    "normalmap-diffuse-grazing": ({"type": "normalmap", "normalmap": {"type": "rgb", "value": [0.9, 0.5, 0.7]},
                                   "bsdf": {"type": "diffuse"}}, [-0.9, 0.1, 0.2], (0.5, 0.5), None),
    "bumpmap-roughplastic": ({"type": "bumpmap", "scale": 0.5,
                              "h": {"type": "bitmap", "filename": "perturbed_height.png", "raw": True},
                              "bsdf": {"type": "roughplastic", "alpha": 0.3, "distribution": "ggx"}},
                             [0.5, 0.3, 0.8], (0.31, 0.58), 0.3),
}


@pytest.mark.parametrize("name", sorted(TILTED))
def test_chi2_sample_vs_pdf_of_a_tilted_frame(ctx, queue, name):
    d, wi, uv, alpha = TILTED[name]
    rows, tex = rows_of(d)
    wi = np.asarray(wi, np.float64) / np.linalg.norm(wi)
    s = bsdf_sample_batch(ctx, queue, rows, wi, N_SAMPLES, seed=5, uv=uv, textures=tex)
    keep = np.any(s.weight != 0, axis=1)
    assert keep.mean() > 0.5
    # the frame is tilted: the samples' mean direction is not the shading normal's
    mean = s.wo[keep].mean(axis=0)
    assert np.hypot(mean[0], mean[1]) > 0.05, f"{name}: the samples look unperturbed: mean {mean}"
    peaks = []
    if alpha is not None:
        m = s.wo[keep][np.argmax(s.pdf[keep])]          # the lobe's peak, wherever the tilt put it
        peaks = [(m, min(14 * alpha, np.pi)), (m, 4 * alpha)]
    dirs, w, cell = refined_direction_grid(RES, SUB, peaks, n_fine=300)
    pdf, _ = bsdf_pdf_eval_batch(ctx, queue, rows, wi, dirs, uv=uv, textures=tex)
    exp = expected_from_grid(pdf, w, cell, (RES, 2 * RES), N_SAMPLES)
    res = chi2_test(bin_directions(s.wo[keep], RES), exp, min_exp=5.0, alpha=0.01, n_tests=len(TILTED))
    assert res.passed, f"{name}: {res.message}"
    # what survives is what the pdf integrates to (the rest crossed a horizon and weighs 0)
    sigma = np.sqrt(keep.mean() * (1 - keep.mean()) / N_SAMPLES)
    assert abs(exp.sum() / N_SAMPLES - keep.mean()) < 5 * sigma + 3e-3
    # weight == f cos / pdf, with f holding the terminator's shadowing as the weight does
    wk, fk, pk, cos = s.weight[keep], s.f[keep], s.pdf[keep], np.abs(s.wo[keep, 2])
    assert np.all(s.measure[keep] == 0) and np.all(pk > 0)
    # (eval restates a sampled wo in the tilted frame once more: near the horizon that float32 round trip moves the
    # cosine ratio by a few 1e-4, in a handful of samples per million)
    want = fk * (cos / pk)[:, None]
    np.testing.assert_allclose(wk, want, rtol=2e-3, atol=1e-7)
    assert np.count_nonzero(~np.isclose(wk, want, rtol=2e-4, atol=1e-7)) < 1e-4 * wk.size


# ------------------------------------------------------------------------------------------- scene errors
def test_a_height_texture_without_a_gradient_is_a_located_error():
    d = {"type": "bumpmap", "t": {"type": "checkerboard"}, "bsdf": {"type": "diffuse"}}
    with pytest.raises(SceneError, match="eval_1_grad"):
        create(spec(d))


@pytest.mark.parametrize("d, match", [
    ({"type": "bumpmap", "bsdf": {"type": "diffuse"}}, "one nested <texture>"),
    ({"type": "bumpmap", "h": {"type": "bitmap", "filename": "perturbed_height.png"}}, "one nested <bsdf>"),
    ({"type": "normalmap", "bsdf": {"type": "diffuse"}}, "needs a normal map"),
    ({"type": "normalmap", "normalmap": {"type": "rgb", "value": [0.5, 0.5, 1]}}, "nested <bsdf>"),
], ids=["bumpmap-no-texture", "bumpmap-no-bsdf", "normalmap-no-map", "normalmap-no-bsdf"])
def test_missing_children_are_errors(d, match):
    with pytest.raises(SceneError, match=match):
        create(spec(d))


def test_nesting_deeper_than_the_dispatch_is_a_located_error():
    from clrender.device import dispatch

    d = {"type": "diffuse"}
    for _ in range(dispatch.BSDF.composite_levels + 1):
        d = {"type": "normalmap", "normalmap": {"type": "rgb", "value": [0.5, 0.5, 1]}, "bsdf": d}
    with pytest.raises(SceneError, match="nested 4 deep; at most 3 levels"):
        create(spec(d))


# ------------------------------------------------------------------------------------------- aov sh_normal
AOV_SCENE = """<scene version="3.0.0">
    <integrator type="aov"><string name="aovs" value="nn:sh_normal"/></integrator>
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="1"/></sampler>
        <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle">{bsdf}</shape>
</scene>"""
NM = '<bsdf type="normalmap"><rgb name="normalmap" value="0.8, 0.5, 0.9"/><bsdf type="diffuse"/></bsdf>'


@pytest.mark.parametrize("bsdf, want", [
    ('<bsdf type="diffuse"/>', [0, 0, 1]),
    (NM, [0.6, 0, 0.8]),
    (f'<bsdf type="twosided">{NM}</bsdf>', [0, 0, 1]),
], ids=["diffuse", "normalmap", "twosided-normalmap"])
def test_aov_sh_normal_is_the_perturbed_normal(tmp_path, bsdf, want):
    """Mitsuba 3.9.1's aov shows a top-level normalmap's normal as sh_normal (BSDF::sh_frame), not a nested one's:
    these values are what it renders for these scenes."""
    import clrender

    path = tmp_path / "aov.xml"
    path.write_text(AOV_SCENE.format(bsdf=bsdf))
    film = clrender.render(clrender.load_scene(path), seed=1)
    np.testing.assert_allclose(film.image[1:3, 1:3].reshape(-1, 3), np.broadcast_to(want, (4, 3)), atol=1e-5)
