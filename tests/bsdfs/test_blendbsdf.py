"""Mitsuba 3's blendbsdf (a composite: clrender/bsdfs/blendbsdf.py, kernels/bsdfs/blendbsdf.h) on the device:
chi-square of its sampling against its own pdf, weight == f cos/pdf for smooth samples and its children's delta
samples with their weights and frequencies, eval and pdf as the weighted sums of its children's, energy, a textured
weight, eval against Mitsuba 3's own values, a furnace render, and the located errors.

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
                            check_values, check_weights, chi2_case_of, rows_of, value_cases, wi_at)

#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("blendbsdf", "plastic", "roughplastic"), textures=("checkerboard_color",), levels=1)


ROUGH = {"type": "roughplastic", "alpha": 0.2, "distribution": "ggx"}
CASES = [("blend-rough-plastic-30", {"type": "blendbsdf", "weight": 0.35, "a": ROUGH, "b": {"type": "plastic"}},
          30.0, False, 0.2)]
N_CHI2 = FAMILIES["coated-chi2"]
chi2_case = chi2_case_of(CASES)


@pytest.mark.plugin("blendbsdf", "sampling")
@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_chi2_sample_vs_pdf(chi2_runs, name):
    chi2_runs.check(name)


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_weights(chi2_runs, name):
    check_weights(chi2_runs[name])


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_pdf_integral(chi2_runs, name):
    check_smooth_pdf_integral(chi2_runs[name], name)


@pytest.mark.plugin("blendbsdf", "sampling")
def test_mask_and_blend_with_delta_children(ctx, queue):
    """A blend of plastic (delta + diffuse) and roughplastic keeps the plastic's delta weight on its delta samples
    and weighs smooth ones by the mixture; its eval/pdf are the weighted sums of the children's smooth parts. (The
    mask's half is in test_mask.py.)"""
    n = 200000
    wi = wi_at(35.0)
    child = rows_of({"type": "plastic"})
    wo = np.array([[0.3, 0.2, 0.9], [-0.5, 0.1, 0.6]])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    pc, fc = bsdf_pdf_eval_batch(ctx, queue, child, wi, wo)
    blend = rows_of({"type": "blendbsdf", "weight": 0.4, "a": {"type": "plastic"},
                     "b": {"type": "roughplastic", "alpha": 0.3}})
    rough = rows_of({"type": "roughplastic", "alpha": 0.3})
    pb, fb = bsdf_pdf_eval_batch(ctx, queue, blend, wi, wo)
    pr, fr = bsdf_pdf_eval_batch(ctx, queue, rough, wi, wo)
    np.testing.assert_allclose(fb, 0.6 * fc + 0.4 * fr, rtol=1e-5)
    np.testing.assert_allclose(pb, 0.6 * pc + 0.4 * pr, rtol=1e-5)
    smp = bsdf_sample_batch(ctx, queue, blend, wi, n, 10)
    plastic_smp = bsdf_sample_batch(ctx, queue, child, wi, n, 10)
    d_blend = smp.measure == 1
    d_plastic = plastic_smp.measure == 1
    # the plastic's delta weight, chosen with probability 0.6 x its own delta probability
    np.testing.assert_allclose(smp.weight[d_blend], np.tile(plastic_smp.weight[d_plastic][0], (d_blend.sum(), 1)),
                               rtol=1e-6)
    p = 0.6 * d_plastic.mean()
    assert abs(d_blend.mean() - p) < 6 * np.sqrt(p * (1 - p) / n)


def test_energy(ctx, queue):
    check_energy(ctx, queue, {"type": "blendbsdf", "weight": 0.5, "a": {"type": "plastic"},
                              "b": {"type": "roughplastic"}})


@pytest.mark.parametrize("d,match", [
    ({"type": "blendbsdf", "weight": 1.5, "a": {"type": "plastic"}, "b": {"type": "plastic"}}, r"weight must be"),
    ({"type": "blendbsdf", "a": {"type": "plastic"}}, "needs 2 nested <bsdf>, got 1"),
])
def test_errors(d, match):
    with pytest.raises(SceneError, match=match):
        create(spec_from_dict(d))


def test_fraction_parameter_errors():
    check_fraction_parameter_errors({"type": "blendbsdf", "a": {"type": "plastic"}, "b": {"type": "plastic"}},
                                    "weight", "a")


def test_textured_parameters(ctx, queue):
    rough = {"type": "roughplastic", "alpha": 0.3}
    check_textured(ctx, queue, {"type": "blendbsdf", "a": {"type": "plastic"}, "b": rough}, "weight", (0.2,) * 3,
                   (0.9,) * 3, lambda v: {"type": "blendbsdf", "weight": v[0], "a": {"type": "plastic"}, "b": rough})


@pytest.mark.plugin("blendbsdf", "eval")
@pytest.mark.parametrize("data,case", value_cases("blendbsdf"))
def test_eval_and_pdf_match_mitsuba(ctx, queue, data, case):
    check_values(ctx, queue, data, case)


@pytest.mark.plugin("blendbsdf", "render")
def test_furnace_render(tmp_path):
    """A blend of 3/4 diffuse 0.8 and 1/4 perfect mirror (weight 0.25: the second child's share) in a constant
    environment of radiance 1 (Mitsuba's path) shows 0.75 x 0.8 + 0.25 = 0.85."""
    xml = ('<bsdf type="blendbsdf"><float name="weight" value="0.25"/><bsdf type="diffuse"><rgb name="reflectance" '
           'value="0.8"/></bsdf><bsdf type="conductor"/></bsdf>')
    check_render_value(render_furnace_plane(tmp_path, xml), 0.85)
