"""Nori's and Mitsuba's diffuse BSDF (clrender/bsdfs/diffuse.py, kernels/bsdfs/diffuse.h) on the device: chi-square
of sample() against pdf(), sample weights against eval()·cos/pdf(), eval and pdf against the formulas, energy (a
white furnace), and a check that the chi-square machinery rejects a wrong pdf.

All chi-square cases of this module share one Šidák correction (N_CHI2 tests at overall level ALPHA).
"""
import numpy as np
import pytest

from clrender.testing.plugin_checks import (ALPHA, FAMILIES, bsdf_chi2, bsdf_pdf_eval_batch, bsdf_sample_batch,
                                            check_render_value, check_weights, chi2_test, lobe_grid, plugin_row,
                                            render_furnace_plane, wi_at)

ANGLES = (0.0, 30.0, 60.0, 85.0)


def _c(v):
    return ", ".join(repr(float(x)) for x in np.broadcast_to(np.asarray(v, np.float64), (3,)))


def row_diffuse(albedo):
    return plugin_row(f'<bsdf type="diffuse"><color name="albedo" value="{_c(albedo)}"/></bsdf>')


CASES = {f"diffuse-grey-{th:g}": (0.5, th) for th in ANGLES}
CASES["diffuse-colour-30"] = ((0.2, 0.5, 0.9), 30.0)
N_CHI2 = FAMILIES["nori-bsdf-chi2"]


def chi2_case(name):
    albedo, th = CASES[name]
    return row_diffuse(albedo), wi_at(th), lobe_grid(wi_at(th), None)


@pytest.mark.plugin("diffuse", "sampling")
@pytest.mark.parametrize("name", list(CASES))
def test_chi2_sample_vs_pdf(chi2_runs, name):
    chi2_runs.check(name)


@pytest.mark.parametrize("name", list(CASES))
def test_weight_is_eval_cos_over_pdf(chi2_runs, name):
    run = chi2_runs[name]
    check_weights(run.samples, run.keep)


@pytest.mark.plugin("diffuse", "eval")
def test_diffuse_eval_pdf(ctx, queue):
    row = row_diffuse((0.2, 0.5, 0.9))
    wo = np.array([[0, 0, 1], [0.6, 0, 0.8], [0, 0.6, -0.8], [1, 0, 0]], float)
    pdf, f = bsdf_pdf_eval_batch(ctx, queue, row, (0, 0, 1), wo)
    np.testing.assert_allclose(pdf, [1 / np.pi, 0.8 / np.pi, 0, 0], rtol=1e-6)
    np.testing.assert_allclose(f[:2], np.tile(np.array([0.2, 0.5, 0.9]) / np.pi, (2, 1)), rtol=1e-6)
    assert np.all(f[2:] == 0)
    # wi below the surface: nothing
    pdf, f = bsdf_pdf_eval_batch(ctx, queue, row, (0, 0.6, -0.8), wo)
    assert np.all(pdf == 0) and np.all(f == 0)
    s = bsdf_sample_batch(ctx, queue, row, (0, 0.6, -0.8), 1000, 1)
    assert np.all(s.weight == 0)


def test_chi2_rejects_wrong_pdfs(ctx, queue):
    # cosine-weighted samples scored against the uniform hemisphere density
    _, _, obs, exp = bsdf_chi2(ctx, queue, row_diffuse(0.5), wi_at(30.0), lobe_grid(wi_at(30.0), None),
                               pdf_fn=lambda d: np.where(d[:, 2] > 0, 1 / (2 * np.pi), 0.0))
    assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed


def test_diffuse_white_furnace(ctx, queue):
    for th in ANGLES:
        s = bsdf_sample_batch(ctx, queue, row_diffuse(1.0), wi_at(th), 200000, 11)
        assert np.all(s.weight == 1.0)


# ------------------------------------------------------------------------------------------- render
@pytest.mark.plugin("diffuse", "render")
# one render in the default run (each builds its own program: seconds), both with the slow suites
@pytest.mark.parametrize("fmt", ["nori", pytest.param("mitsuba", marks=pytest.mark.slow)])
def test_furnace_render(tmp_path, fmt):
    """A diffuse plane in a constant environment of radiance 1 (path_mis, Mitsuba's path) shows its albedo."""
    xml = {"nori": '<bsdf type="diffuse"><color name="albedo" value="0.2, 0.5, 0.9"/></bsdf>',
           "mitsuba": '<bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.5, 0.9"/></bsdf>'}[fmt]
    check_render_value(render_furnace_plane(tmp_path, xml, fmt), (0.2, 0.5, 0.9))
