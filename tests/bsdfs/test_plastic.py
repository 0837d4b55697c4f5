"""Mitsuba 3's smooth plastic (clrender/bsdfs/plastic.py, kernels/bsdfs/plastic.h) on the device: chi-square of its
smooth lobe's sampling against its own pdf, weight == f cos/pdf for smooth samples and the exact delta samples of the
coating (direction, frequency, weight against the formulas), the pdf's integral (= 1 - the coating's probability),
energy (sampling mean == quadrature of eval plus the coating), eval against Mitsuba 3's own values, a textured
diffuse_reflectance, a furnace render, the located errors, and a check that the chi-square catches a wrong pdf.

All chi-square cases share one Šidák correction (N_CHI2 tests at overall level ALPHA)."""
import numpy as np
import pytest

from clrender.errors import SceneError
from clrender.scene.registry import create
from clrender.testing.mitsuba_dict import spec_from_dict
from clrender.testing.plugin_checks import (ALPHA, FAMILIES, FURNACE_THETA, bsdf_chi2, bsdf_pdf_eval_batch,
                                            bsdf_sample_batch, check_render_value, chi2_test, fresnel, lobe_grid,
                                            render_furnace_plane)

from .coated_common import (CHI2_SEED, albedo_quadrature, check_energy, check_smooth_pdf_integral, check_textured,
                            check_values, check_weights, chi2_case_of, rgb, rows_of, value_cases, wi_at)

#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("plastic",), textures=("checkerboard_color",))


CASES = [(f"plastic-{th:g}", {"type": "plastic", "diffuse_reflectance": rgb(0.2, 0.5, 0.8)}, th, False, None)
         for th in (0.0, 40.0, 85.0)]
CASES.append(("plastic-ior2.2-nonlinear-60", {"type": "plastic", "int_ior": 2.2, "nonlinear": True}, 60.0, False,
              None))
N_CHI2 = FAMILIES["coated-chi2"]
chi2_case = chi2_case_of(CASES)


@pytest.mark.plugin("plastic", "sampling")
@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_chi2_sample_vs_pdf(chi2_runs, name):
    chi2_runs.check(name)


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_weights(chi2_runs, name):
    check_weights(chi2_runs[name])


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_pdf_integral(chi2_runs, name):
    check_smooth_pdf_integral(chi2_runs[name], name)


def fresnel_ext1(c, eta):
    s2 = (1 - c * c) / (eta * eta)
    ct = np.sqrt(np.maximum(0, 1 - s2))
    rs = (c - eta * ct) / (c + eta * ct)
    rp = (eta * c - ct) / (eta * c + ct)
    return 0.5 * (rs * rs + rp * rp)


@pytest.mark.plugin("plastic", "sampling")
def test_plastic_specular_lobe(ctx, queue):
    """Mitsuba's rule: specular with probability F s / (F s + (1-F)(1-s)), s = mean(spec) / (mean(diff) + mean(spec)),
    weight spec F / p; the diffuse lobe f = d / (1 - Fdr(1/eta)) (1-F_i)(1-F_o) / (pi eta^2)."""
    d, sp, eta = np.array([0.2, 0.5, 0.8]), np.array([0.9, 0.7, 0.6]), 1.7
    rows = rows_of({"type": "plastic", "diffuse_reflectance": rgb(*d), "specular_reflectance": rgb(*sp),
                    "int_ior": eta, "ext_ior": 1.0})
    for th in (0.0, 50.0, 80.0):
        wi = wi_at(th)
        F = fresnel_ext1(wi[2], eta)
        s = sp.mean() / (sp.mean() + d.mean())
        p = F * s / (F * s + (1 - F) * (1 - s))
        n = 200000
        smp = bsdf_sample_batch(ctx, queue, rows, wi, n, 3)
        delta = smp.measure == 1
        assert abs(delta.mean() - p) < 5 * np.sqrt(p * (1 - p) / n)
        np.testing.assert_allclose(smp.weight[delta], np.tile(sp * F / p, (delta.sum(), 1)), rtol=1e-4)
        x = 1 / eta
        fdr = -1.4399 * x * x + 0.7099 * x + 0.6681 + 0.0636 / x
        wo = np.array([[0.3, 0.2, 0.9], [0.0, 0.0, 1.0], [-0.9, 0.1, 0.2]])
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        pdf, f = bsdf_pdf_eval_batch(ctx, queue, rows, wi, wo)
        ref = d[None, :] / (1 - fdr) * ((1 - F) * (1 - fresnel_ext1(wo[:, 2], eta)))[:, None] / (np.pi * eta * eta)
        np.testing.assert_allclose(f, ref, rtol=1e-4)
        np.testing.assert_allclose(pdf, (1 - p) * wo[:, 2] / np.pi, rtol=1e-4)


ENERGY = [
    ("plastic-white", {"type": "plastic", "diffuse_reflectance": rgb(1, 1, 1)}),
    ("plastic-nonlinear", {"type": "plastic", "diffuse_reflectance": rgb(0.9, 0.9, 0.9), "nonlinear": True}),
]


@pytest.mark.parametrize("name,d", ENERGY, ids=[e[0] for e in ENERGY])
def test_energy(ctx, queue, name, d):
    check_energy(ctx, queue, d)


def test_chi2_catches_a_wrong_pdf(ctx, queue):
    """The diffuse lobe chosen with the wrong probability (the plastic's spec weight changes the pdf, not f) fails
    the chi-square test."""
    wi = wi_at(30.0)
    rows = rows_of({"type": "plastic", "diffuse_reflectance": rgb(0.2, 0.2, 0.2)})
    other = rows_of({"type": "plastic", "diffuse_reflectance": rgb(0.2, 0.2, 0.2),
                     "specular_reflectance": rgb(0.5, 0.5, 0.5)})
    _, _, obs, exp = bsdf_chi2(ctx, queue, rows, wi, lobe_grid(wi, None), seed=CHI2_SEED,
                               pdf_fn=lambda dirs: bsdf_pdf_eval_batch(ctx, queue, other, wi, dirs)[0])
    assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed


@pytest.mark.parametrize("d,match", [
    ({"type": "plastic", "int_ior": "unobtainium"}, "unknown index of refraction name"),
    ({"type": "plastic", "int_ior": 1.000277}, "must differ"),
])
def test_errors(d, match):
    with pytest.raises(SceneError, match=match):
        create(spec_from_dict(d))


def test_textured_parameters(ctx, queue):
    check_textured(ctx, queue, {"type": "plastic"}, "diffuse_reflectance", (0.9, 0.2, 0.1), (0.1, 0.5, 0.3),
                   lambda v: {"type": "plastic", "diffuse_reflectance": rgb(*v)})


@pytest.mark.plugin("plastic", "eval")
@pytest.mark.parametrize("data,case", value_cases("plastic"))
def test_eval_and_pdf_match_mitsuba(ctx, queue, data, case):
    check_values(ctx, queue, data, case)


@pytest.mark.plugin("plastic", "render")
def test_furnace_render(ctx, queue, tmp_path):
    """A plastic plane in a constant environment of radiance 1 (Mitsuba's path) shows its directional albedo: the
    coating's F (the delta lobe) plus the quadrature of its smooth lobe's eval (to 0.3 %)."""
    xml = '<bsdf type="plastic"><rgb name="diffuse_reflectance" value="0.2, 0.5, 0.8"/></bsdf>'
    b = create(spec_from_dict({"type": "plastic", "diffuse_reflectance": rgb(0.2, 0.5, 0.8)}))
    wi = wi_at(FURNACE_THETA)
    F = float(fresnel(wi[2], b.ext_ior, b.int_ior))
    ref = albedo_quadrature(ctx, queue, rows_of({"type": "plastic", "diffuse_reflectance": rgb(0.2, 0.5, 0.8)}), wi)
    check_render_value(render_furnace_plane(tmp_path, xml), ref + F, rel_tol=3e-3)
