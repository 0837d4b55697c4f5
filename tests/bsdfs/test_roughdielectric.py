"""Mitsuba 3's roughdielectric (clrender/bsdfs/roughdielectric.py, kernels/bsdfs/roughdielectric.h) on the device:
chi-square of its sampling against its own pdf (Beckmann and GGX, isotropic and anisotropic, visible normals or not,
from outside and inside, grazing, total internal reflection, a high index), the pdf's integral against the fraction
of samples that survive, weight == f cos / pdf and the refractions' eta, energy (white furnace) and reciprocity,
values against Mitsuba 3 itself (tests/mitsuba/bsdf_values, written by make_bsdf_values.py), textured parameters and
the scene errors.

All chi-square cases share one Šidák correction (N_CHI2 tests at overall level ALPHA).
"""
import numpy as np
import pytest

from clrender.errors import SceneError
from clrender.testing.plugin_checks import (ALPHA, FAMILIES, albedo_quadrature, bsdf_chi2, bsdf_pdf_eval_batch,
                                            bsdf_sample_batch, check_pdf_integral, check_render_value,
                                            check_sample_weights, check_textured_like_constant, chi2_test, furnace_wi,
                                            mean_le, mitsuba_bsdf, mitsuba_rough_cases, mitsuba_row,
                                            render_furnace_plane, sidak, specular_grid, wi_at)

from .mitsuba_values import case_id, check_glossy_values, ref_cases

make, row = mitsuba_bsdf, mitsuba_row


# --------------------------------------------------------------------------------------- chi2 cases
#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("roughdielectric",), textures=("checkerboard_color",))


def _cases():
    cases = []
    for dist in ("beckmann", "ggx"):
        for a in (0.1, 0.5):
            for th, side in ((0.0, 1), (45.0, 1), (80.0, 1), (20.0, -1), (45.0, -1), (80.0, -1)):
                cases.append((f"rd-{dist}-a{a:g}-{th:g}{'in' if side < 0 else 'out'}",
                              dict(distribution=dist, alpha=a), wi_at(th, side), (a,)))
        cases.append((f"rd-{dist}-aniso-40out", dict(distribution=dist, alpha_u=0.05, alpha_v=0.3),
                      wi_at(40.0) @ np.array([[0.6, 0.8, 0], [-0.8, 0.6, 0], [0, 0, 1]]), (0.05, 0.3)))
        cases.append((f"rd-{dist}-diamond-60in", dict(distribution=dist, alpha=0.2, int_ior="diamond"),
                      wi_at(60.0, -1), (0.2,)))
        cases.append((f"rd-{dist}-allnormals-30out", dict(distribution=dist, alpha=0.3, sample_visible=False),
                      wi_at(30.0), (0.3,)))
    return cases


CASES = _cases()
N_CHI2 = FAMILIES["mitsuba-rough-chi2"]
# The default run samples a cross-section (each distribution: both sides, grazing, total internal reflection,
# anisotropic, a high index); the whole sweep is marked slow.
DEFAULT_CASES = {f"rd-{d}-{c}" for d in ("beckmann", "ggx") for c in (
    "a0.1-0out", "a0.5-80out", "a0.1-45in", "a0.5-80in", "aniso-40out", "diamond-60in")}
CASE_PARAMS = [pytest.param(c[0], marks=() if c[0] in DEFAULT_CASES else pytest.mark.slow) for c in CASES]


chi2_case = mitsuba_rough_cases("roughdielectric", CASES)


@pytest.mark.plugin("roughdielectric", "sampling")
@pytest.mark.parametrize("name", CASE_PARAMS)
def test_chi2_sample_vs_pdf(chi2_runs, name):
    chi2_runs.check(name)


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_pdf_integral_is_the_surviving_fraction(chi2_runs, name):
    """∫ pdf = P(a sample survives) <= 1: = 1 up to what visible normals scatter into the wrong side; a binomial
    bound of 5 sigma plus the quadrature's 0.3%."""
    run = chi2_runs[name]
    kept = check_pdf_integral(run.total, run.keep, name)
    if name.endswith("-a0.1-0out"):   # smooth enough that (almost) nothing is lost
        assert kept > 0.99, f"{name}: at normal incidence almost every sample must survive, kept {kept:.4f}"


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_weight_is_eval_cos_over_pdf(chi2_runs, name):
    run = chi2_runs[name]
    s, keep, wi = run.samples, run.keep, run.wi
    refl = check_sample_weights(s, keep, wi)   # eta 1 for reflections; eta_t / eta_i for refractions, below
    if (~refl).any():
        e = s.eta[keep][~refl]
        ratio = 2.419 / 1.000277 if "diamond" in name else 1.5046 / 1.000277
        np.testing.assert_allclose(e, ratio if wi[2] > 0 else 1 / ratio, rtol=1e-5)


def test_chi2_rejects_wrong_pdfs(ctx, queue):
    # visible-normal samples scored against the density of all normals, and a 10% different alpha
    bsdf = make("roughdielectric", distribution="ggx", alpha=0.3)
    wrong = row("roughdielectric", distribution="ggx", alpha=0.3, sample_visible=False)
    _, _, obs, exp = bsdf_chi2(ctx, queue, bsdf.pack(), wi_at(70.0), specular_grid(bsdf, wi_at(70.0), (0.3,)),
                               pdf_row=wrong)
    assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed
    other = row("roughdielectric", distribution="ggx", alpha=0.33)
    _, _, obs, exp = bsdf_chi2(ctx, queue, bsdf.pack(), wi_at(30.0), specular_grid(bsdf, wi_at(30.0), (0.3,)),
                               pdf_row=other)
    assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed


# ------------------------------------------------------------------------------------ energy / furnace
def test_white_furnace(ctx, queue):
    """The reflected plus transmitted importance (weight · eta² for refractions) is at most what arrives, from
    either side, and almost all of it when smooth at normal incidence."""
    cases = [(make("roughdielectric", distribution=dist, alpha=a), wi_at(th, side))
             for dist in ("beckmann", "ggx") for a in (0.1, 0.5, 1.0) for th in (0.0, 60.0, 85.0)
             for side in (1, -1)]
    a_t = sidak(ALPHA, FAMILIES["mitsuba-rough-furnace"])
    for bsdf, wi in cases:
        s = bsdf_sample_batch(ctx, queue, bsdf.pack(), wi, 100000, 41)
        w = s.weight[:, 0].astype(np.float64) * s.eta.astype(np.float64) ** 2
        assert mean_le(w, 1.0, a_t), f"roughdielectric {bsdf.distribution.name} " \
                                     f"{bsdf.distribution.alpha_u} {wi}: mean {w.mean():.5f}"
        if bsdf.distribution.alpha_u[0] == 0.1 and wi[2] > 0.99:
            assert w.mean() > 0.985


def test_reciprocity(ctx, queue):
    """f(wi, wo) = f(wo, wi) for reflection; for refraction f(wo, wi) = (eta_o / eta_i)^2 f(wi, wo) in the radiance
    form (eta_o: the index on wo's side)."""
    rng = np.random.default_rng(17)
    m = 4000
    wi = rng.normal(size=(m, 3))
    wo = rng.normal(size=(m, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    for kw in (dict(alpha=0.4), dict(distribution="ggx", alpha_u=0.3, alpha_v=0.6, int_ior=1.33)):
        bsdf = make("roughdielectric", **kw)
        r = bsdf.pack()
        _, f1 = bsdf_pdf_eval_batch(ctx, queue, np.array([r]), wi, wo, row_index=np.zeros(m))
        _, f2 = bsdf_pdf_eval_batch(ctx, queue, np.array([r]), wo, wi, row_index=np.zeros(m))
        ein, eex = bsdf.int_ior, bsdf.ext_ior
        trans = wi[:, 2] * wo[:, 2] < 0
        eta_o = np.where(wo[:, 2] > 0, eex, ein)
        eta_i = np.where(wi[:, 2] > 0, eex, ein)
        scale = np.where(trans, (eta_o / eta_i) ** 2, 1.0)
        assert (f1[:, 0] > 0).sum() > m // 10
        np.testing.assert_allclose(f2, f1 * scale[:, None], rtol=2e-3, atol=1e-6 * f1.max())


# ----------------------------------------------------------------------------------- against Mitsuba
GLOSSY_REFS = ref_cases(("roughdielectric",))


@pytest.mark.plugin("roughdielectric", "eval")
@pytest.mark.parametrize("case", GLOSSY_REFS, ids=[case_id(c) for c in GLOSSY_REFS])
def test_glossy_values_match_mitsuba(ctx, queue, case):
    check_glossy_values(ctx, queue, case)


def test_textured_parameters(ctx, queue):
    """A textured alpha and specular_transmittance: where the checkerboard shows value1 the BSDF equals the constant
    one with alpha 0.2 and colour value1, elsewhere 0.7 / value2 (directions through the surface)."""
    check_textured_like_constant(ctx, queue, "roughdielectric", ("alpha", "specular_transmittance"),
                                 "specular_transmittance", transmit=True)


@pytest.mark.parametrize("kind,kw,message", [
    ("roughdielectric", dict(alpha=0.1, alpha_u=0.1, alpha_v=0.2), "either alpha or alpha_u"),
    ("roughdielectric", dict(alpha=-0.1), "alpha must be positive"),
])
def test_scene_errors(kind, kw, message):
    with pytest.raises(SceneError, match=message):
        make(kind, **kw)


# ------------------------------------------------------------------------------------------- render
@pytest.mark.plugin("roughdielectric", "render")
# one render in the default run (each builds its own program: seconds), both with the slow suites
@pytest.mark.parametrize("dist", [pytest.param("beckmann", marks=pytest.mark.slow), "ggx"])
def test_furnace_render(ctx, queue, tmp_path, dist):
    """A roughdielectric plane in a constant environment of radiance 1 (Mitsuba's path) shows its directional
    albedo, the quadrature of its eval (to 0.3 %) at the camera's direction."""
    xml = (f'<bsdf type="roughdielectric"><string name="distribution" value="{dist}"/>'
           '<float name="alpha" value="0.3"/></bsdf>')
    bsdf = make("roughdielectric", distribution=dist, alpha=0.3)
    wi = furnace_wi()
    ref = albedo_quadrature(ctx, queue, bsdf.pack(), wi, specular_grid(bsdf, wi, (0.3,)))
    check_render_value(render_furnace_plane(tmp_path, xml), ref, rel_tol=3e-3)
