"""What the test files of Mitsuba 3's normalmap and bumpmap share (kernels/bsdfs/{normalmap,bumpmap,perturb}.h):
the plugins from Mitsuba dicts with their files in tests/mitsuba/bsdf_values, and the checks:

- values against Mitsuba 3.9.1 itself at fixed surface points (uv, shading frame, geometric normal, dp/du, dp/dv)
  and direction pairs: tests/mitsuba/bsdf_values/perturbed.json, written by make_perturbed_values.py in that
  folder (Mitsuba is not needed to run this);
- a flat normal map (0.5, 0.5, 1) and a constant height give exactly the child's values;
- chi-square of the wrapped sampling routine against its own pdf for tilted normals, and weight == f cos / pdf.
"""
import json
from pathlib import Path

import numpy as np

from clrender.scene.registry import create
from clrender.scene.spec import PluginSpec
from clrender.scene.transform import Transform
from clrender.testing.mitsuba_dict import spec_from_dict
from clrender.testing.plugin_checks import (RES, SUB, bin_directions, bsdf_pdf_eval_batch, bsdf_sample_batch,
                                            chi2_test, expected_from_grid, pack_rows, refined_direction_grid)

VALUES = Path(__file__).resolve().parent.parent / "mitsuba" / "bsdf_values"
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


def check_values(ctx, queue, name):
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
    # coated_common.py)
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


def flat_wrappers(child, tmp_path):
    # a constant height: a bitmap of one grey (its slope is 0 everywhere); the normal map: (0.5, 0.5, 1) itself
    from clrender.png import encode_png

    (tmp_path / "flat.png").write_bytes(encode_png(np.full((3, 4, 3), 77, np.uint8)))
    yield "normalmap", {"type": "normalmap", "normalmap": {"type": "rgb", "value": [0.5, 0.5, 1.0]}, "bsdf": child}
    yield "bumpmap", {"type": "bumpmap", "scale": 3.0, "h": {"type": "bitmap", "filename": str(tmp_path / "flat.png")},
                      "bsdf": child}
    yield "bumpmap-nearest", {"type": "bumpmap", "scale": 3.0,
                              "h": {"type": "bitmap", "filename": str(VALUES / "perturbed_height.png"),
                                    "filter_type": "nearest"}, "bsdf": child}


def check_unperturbed_is_the_child(ctx, queue, child, tmp_path, wrapper):
    """A flat normal map and a bump map without slope (those of `flat_wrappers` whose name starts with `wrapper`)
    leave the frame as it is: the child's eval, pdf and samples exactly (the default query geometry: dp/du along
    the shading frame's first axis)."""
    wi, wo = _pairs()
    uv = np.random.default_rng(5).uniform(0, 1, (len(wi), 2))
    crows, ctex = rows_of(FLAT_CHILDREN[child])
    cpdf, cf = bsdf_pdf_eval_batch(ctx, queue, crows, wi, wo, uv=uv, textures=ctex)
    cs = bsdf_sample_batch(ctx, queue, crows, wi, len(wi), seed=11, uv=uv, textures=ctex)
    assert np.count_nonzero(cf.any(axis=1)) > 50 or np.count_nonzero(cs.weight.any(axis=1)) > 50
    for name, d in flat_wrappers(FLAT_CHILDREN[child], tmp_path):
        if not name.startswith(wrapper):
            continue
        rows, tex = rows_of(d)
        pdf, f = bsdf_pdf_eval_batch(ctx, queue, rows, wi, wo, uv=uv, textures=tex)
        np.testing.assert_array_equal(pdf, cpdf, err_msg=name)
        np.testing.assert_array_equal(f, cf, err_msg=name)
        s = bsdf_sample_batch(ctx, queue, rows, wi, len(wi), seed=11, uv=uv, textures=tex)
        for field in ("wo", "weight", "pdf", "measure", "eta", "f"):
            np.testing.assert_array_equal(getattr(s, field), getattr(cs, field), err_msg=f"{name}: {field}")


# ---------------------------------------------------------------------------------- sampling (chi-square)
N_SAMPLES = 400_000


def check_tilted_chi2(ctx, queue, name, d, wi, uv, alpha, n_tests):
    """Chi-square of a wrapper whose frame is tilted (`alpha`: its child's roughness, for the grid), the pdf's
    integral, and weight == f cos / pdf."""
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
    res = chi2_test(bin_directions(s.wo[keep], RES), exp, min_exp=5.0, alpha=0.01, n_tests=n_tests)
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
