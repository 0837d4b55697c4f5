"""Mitsuba 3's mask (an opacity over a child: clrender/bsdfs/mask.py, kernels/bsdfs/mask.h) on the device:
chi-square of its sampling against its own pdf (also around a twosided blend, from the back), weight == f cos/pdf for
smooth samples and its pass-through's delta samples, frequency and weight, eval and pdf as opacity x its child's,
nesting three composite levels deep, energy, a textured opacity, eval against Mitsuba 3's own values, a furnace
render, and the located errors.

All chi-square cases share one Šidák correction (N_CHI2 tests at overall level ALPHA)."""
import numpy as np
import pytest

from clrender.errors import SceneError
from clrender.scene.registry import create
from clrender.testing.mitsuba_dict import spec_from_dict
from clrender.testing.plugin_checks import (FAMILIES, bsdf_pdf_eval_batch, bsdf_sample_batch, check_render_value,
                                            render_furnace_plane)

from .coated_common import CHI2_SEED  # noqa: F401 (read by conftest.py's chi2_runs)
from .coated_common import (check_energy, check_fraction_parameter_errors, check_smooth_pdf_integral, check_textured,
                            check_values, check_weights, chi2_case_of, rgb, rows_of, value_cases, wi_at)

#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("mask", "blendbsdf", "plastic", "roughplastic", "twosided"), textures=("checkerboard_color",),
               levels=3)


ROUGH = {"type": "roughplastic", "alpha": 0.2, "distribution": "ggx"}
CASES = [
    ("mask-rough-50", {"type": "mask", "opacity": 0.6, "a": ROUGH}, 50.0, False, 0.2),
    ("mask-twosided-blend-back-70",
     {"type": "mask", "opacity": 0.75, "a": {"type": "twosided", "a": {
         "type": "blendbsdf", "weight": 0.5, "a": {"type": "plastic"}, "b": ROUGH}}}, 70.0, True, 0.2),
]
N_CHI2 = FAMILIES["coated-chi2"]
chi2_case = chi2_case_of(CASES)


@pytest.mark.plugin("mask", "sampling")
@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_chi2_sample_vs_pdf(chi2_runs, name):
    chi2_runs.check(name)


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_weights(chi2_runs, name):
    check_weights(chi2_runs[name])


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_pdf_integral(chi2_runs, name):
    check_smooth_pdf_integral(chi2_runs[name], name)


@pytest.mark.plugin("mask", "sampling")
def test_mask_and_blend_with_delta_children(ctx, queue):
    """A mask passes straight through with probability 1 - opacity (weight 1), and its eval/pdf are opacity x its
    child's. (The blend's half is in test_blendbsdf.py.)"""
    n = 200000
    wi = wi_at(35.0)
    rows = rows_of({"type": "mask", "opacity": 0.3, "a": {"type": "plastic"}})
    smp = bsdf_sample_batch(ctx, queue, rows, wi, n, 9)
    through = np.all(np.abs(smp.wo + wi) < 1e-6, axis=1)
    assert abs(through.mean() - 0.7) < 5 * np.sqrt(0.21 / n)
    assert np.all(smp.measure[through] == 1) and np.all(smp.weight[through] == 1.0)
    child = rows_of({"type": "plastic"})
    wo = np.array([[0.3, 0.2, 0.9], [-0.5, 0.1, 0.6]])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    pm, fm = bsdf_pdf_eval_batch(ctx, queue, rows, wi, wo)
    pc, fc = bsdf_pdf_eval_batch(ctx, queue, child, wi, wo)
    np.testing.assert_allclose(fm, 0.3 * fc, rtol=1e-6)
    np.testing.assert_allclose(pm, 0.3 * pc, rtol=1e-6)


def test_three_levels_of_nesting_render_the_innermost(ctx, queue):
    """mask(mask(mask(plastic))) at opacity 1 is the plastic itself, through three composite levels."""
    d = {"type": "plastic", "diffuse_reflectance": rgb(0.3, 0.6, 0.9)}
    nested = {"type": "mask", "opacity": 1.0, "a": {"type": "mask", "opacity": 1.0,
                                                    "a": {"type": "mask", "opacity": 1.0, "a": d}}}
    wi = wi_at(30.0)
    wo = np.array([[0.3, 0.2, 0.9], [-0.5, 0.1, 0.6]])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    p1, f1 = bsdf_pdf_eval_batch(ctx, queue, rows_of(nested), wi, wo)
    p0, f0 = bsdf_pdf_eval_batch(ctx, queue, rows_of(d), wi, wo)
    assert np.all(f0 > 0)
    np.testing.assert_array_equal(f1, f0)
    np.testing.assert_array_equal(p1, p0)


def test_energy(ctx, queue):
    check_energy(ctx, queue, {"type": "mask", "opacity": 0.5, "a": {"type": "roughplastic", "alpha": 0.4}})


@pytest.mark.parametrize("d,match", [
    ({"type": "mask", "opacity": -0.1, "a": {"type": "plastic"}}, "opacity must be"),
    ({"type": "mask", "a": {"type": "mask", "a": {"type": "mask", "a": {"type": "mask", "a": {"type": "plastic"}}}}},
     "nested 4 deep; at most 3 levels"),
])
def test_errors(d, match):
    with pytest.raises(SceneError, match=match):
        create(spec_from_dict(d))


def test_fraction_parameter_errors():
    check_fraction_parameter_errors({"type": "mask", "a": {"type": "plastic"}}, "opacity", "an")


def test_textured_parameters(ctx, queue):
    rough = {"type": "roughplastic", "alpha": 0.3}
    check_textured(ctx, queue, {"type": "mask", "a": rough}, "opacity", (0.25,) * 3, (0.7,) * 3,
                   lambda v: {"type": "mask", "opacity": v[0], "a": rough})


@pytest.mark.plugin("mask", "eval")
@pytest.mark.parametrize("data,case", value_cases("mask"))
def test_eval_and_pdf_match_mitsuba(ctx, queue, data, case):
    check_values(ctx, queue, data, case)


@pytest.mark.plugin("mask", "render")
def test_furnace_render(tmp_path):
    """A mask of opacity 0.3 over a diffuse 0.5 in a constant environment of radiance 1 (Mitsuba's path): 0.7 of
    the environment seen through it plus 0.3 x 0.5."""
    xml = ('<bsdf type="mask"><float name="opacity" value="0.3"/><bsdf type="diffuse"><rgb name="reflectance" '
           'value="0.5"/></bsdf></bsdf>')
    check_render_value(render_furnace_plane(tmp_path, xml), 0.85)
