"""Mitsuba 3's roughconductor (clrender/bsdfs/roughconductor.py, kernels/bsdfs/roughconductor.h) on the device:
chi-square of its sampling against its own pdf (Beckmann and GGX, isotropic and anisotropic, visible normals or not,
grazing), the pdf's integral against the fraction of samples that survive, weight == f cos / pdf, energy (white
furnace) and reciprocity, values against Mitsuba 3 itself (tests/mitsuba/bsdf_values, written by
make_bsdf_values.py), textured parameters and the scene errors.

All chi-square cases share one Šidák correction (N_CHI2 tests at overall level ALPHA).
"""
import numpy as np
import pytest

from clrender.device.dispatch import flag_defines
from clrender.errors import SceneError
from clrender.testing.plugin_checks import (ALPHA, FAMILIES, UV1, UV2, albedo_quadrature, bsdf_chi2,
                                            bsdf_pdf_eval_batch, bsdf_sample_batch, check_pdf_integral,
                                            check_render_value, check_sample_weights, check_textured_like_constant,
                                            chi2_test, furnace_wi, mean_le, mitsuba_bsdf, mitsuba_bsdf_with_checkers,
                                            mitsuba_rough_cases, mitsuba_row, render_furnace_plane, sidak,
                                            specular_grid, wi_at)

from .mitsuba_values import case_id, check_glossy_values, ref_cases, values

make, row = mitsuba_bsdf, mitsuba_row


# --------------------------------------------------------------------------------------- chi2 cases
#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("roughconductor", "conductor", "dielectric", "thindielectric"), textures=("checkerboard_color",))


def _cases():
    cases = []
    for dist in ("beckmann", "ggx"):
        for a in (0.05, 0.3, 0.8):
            for th in (0.0, 45.0, 80.0, 88.0):
                cases.append((f"rc-{dist}-a{a:g}-{th:g}", dict(distribution=dist, alpha=a), wi_at(th), (a,)))
        for th in (30.0, 75.0):
            cases.append((f"rc-{dist}-aniso-{th:g}", dict(distribution=dist, alpha_u=0.05, alpha_v=0.4, material="Au"),
                          wi_at(th) @ np.array([[0.8, 0.6, 0], [-0.6, 0.8, 0], [0, 0, 1]]), (0.05, 0.4)))
        cases.append((f"rc-{dist}-allnormals-60", dict(distribution=dist, alpha=0.3, sample_visible=False),
                      wi_at(60.0), (0.3,)))
    return cases


CASES = _cases()
N_CHI2 = FAMILIES["mitsuba-rough-chi2"]
# The default run samples a cross-section (each distribution: grazing, anisotropic, all normals); the whole sweep
# is marked slow.
DEFAULT_CASES = {f"rc-{d}-{c}" for d in ("beckmann", "ggx") for c in ("a0.3-45", "a0.05-88", "aniso-75",
                                                                         "allnormals-60")}
CASE_PARAMS = [pytest.param(c[0], marks=() if c[0] in DEFAULT_CASES else pytest.mark.slow) for c in CASES]


chi2_case = mitsuba_rough_cases("roughconductor", CASES)


@pytest.mark.plugin("roughconductor", "sampling")
@pytest.mark.parametrize("name", CASE_PARAMS)
def test_chi2_sample_vs_pdf(chi2_runs, name):
    chi2_runs.check(name)


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_pdf_integral_is_the_surviving_fraction(chi2_runs, name):
    """∫ pdf = P(a sample survives) <= 1: = 1 up to what visible normals scatter below the horizon; a binomial
    bound of 5 sigma plus the quadrature's 0.3%."""
    run = chi2_runs[name]
    kept = check_pdf_integral(run.total, run.keep, name)
    if name.endswith("-a0.05-0"):   # smooth enough that (almost) nothing is lost
        assert kept > 0.99, f"{name}: at normal incidence almost every sample must survive, kept {kept:.4f}"


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_weight_is_eval_cos_over_pdf(chi2_runs, name):
    run = chi2_runs[name]
    check_sample_weights(run.samples, run.keep, run.wi)


def test_chi2_rejects_wrong_pdfs(ctx, queue):
    # visible-normal samples scored against the density of all normals, and a 10% different alpha
    for dist in ("ggx", "beckmann"):
        bsdf = make("roughconductor", distribution=dist, alpha=0.3)
        wrong = row("roughconductor", distribution=dist, alpha=0.3, sample_visible=False)
        _, _, obs, exp = bsdf_chi2(ctx, queue, bsdf.pack(), wi_at(70.0), specular_grid(bsdf, wi_at(70.0), (0.3,)),
                                   pdf_row=wrong)
        assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed, dist
        other = row("roughconductor", distribution=dist, alpha=0.33)
        _, _, obs, exp = bsdf_chi2(ctx, queue, bsdf.pack(), wi_at(30.0), specular_grid(bsdf, wi_at(30.0), (0.3,)),
                                   pdf_row=other)
        assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed, dist
    # anisotropy turned by 90 degrees
    bsdf = make("roughconductor", alpha_u=0.1, alpha_v=0.3)
    _, _, obs, exp = bsdf_chi2(ctx, queue, bsdf.pack(), wi_at(50.0), specular_grid(bsdf, wi_at(50.0), (0.1, 0.3)),
                               pdf_row=row("roughconductor", alpha_u=0.3, alpha_v=0.1))
    assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed


# ------------------------------------------------------------------------------------ energy / furnace
def test_white_furnace(ctx, queue):
    """A lossless rough mirror (material none: F = 1) returns at most what arrives (Smith's single scattering loses
    the rest), and almost all of it when smooth at normal incidence."""
    cases = [(make("roughconductor", distribution=dist, alpha=a), wi_at(th))
             for dist in ("beckmann", "ggx") for a in (0.1, 0.5, 1.0) for th in (0.0, 60.0, 85.0)]
    a_t = sidak(ALPHA, FAMILIES["mitsuba-rough-furnace"])
    for bsdf, wi in cases:
        s = bsdf_sample_batch(ctx, queue, bsdf.pack(), wi, 100000, 41)
        w = s.weight[:, 0].astype(np.float64) * s.eta.astype(np.float64) ** 2
        assert mean_le(w, 1.0, a_t), f"roughconductor {bsdf.distribution.name} " \
                                     f"{bsdf.distribution.alpha_u} {wi}: mean {w.mean():.5f}"
        if bsdf.distribution.alpha_u[0] == 0.1 and wi[2] > 0.99:
            assert w.mean() > 0.985


def test_reciprocity(ctx, queue):
    """f(wi, wo) = f(wo, wi)."""
    rng = np.random.default_rng(17)
    m = 4000
    wi = rng.normal(size=(m, 3))
    wo = rng.normal(size=(m, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    for kw in (dict(alpha_u=0.2, alpha_v=0.5, material="Cu"), dict(distribution="ggx", alpha=0.3)):
        r = make("roughconductor", **kw).pack()
        _, f1 = bsdf_pdf_eval_batch(ctx, queue, np.array([r]), wi, wo, row_index=np.zeros(m))
        _, f2 = bsdf_pdf_eval_batch(ctx, queue, np.array([r]), wo, wi, row_index=np.zeros(m))
        assert (f1[:, 0] > 0).sum() > m // 10
        np.testing.assert_allclose(f2, f1, rtol=2e-3, atol=1e-6 * f1.max())


# ----------------------------------------------------------------------------------- against Mitsuba
GLOSSY_REFS = ref_cases(("roughconductor",))


@pytest.mark.plugin("roughconductor", "eval")
@pytest.mark.parametrize("case", GLOSSY_REFS, ids=[case_id(c) for c in GLOSSY_REFS])
def test_glossy_values_match_mitsuba(ctx, queue, case):
    check_glossy_values(ctx, queue, case)


def test_reference_file_is_mitsubas():
    """(The reference file of every conductor and dielectric, read by their test files through mitsuba_values.py.)"""
    v = values()
    assert v["mitsuba_version"].startswith("3.") and v["variant"] == "scalar_rgb"
    assert {c["type"] for c in v["cases"]} == {"conductor", "roughconductor", "dielectric", "thindielectric",
                                               "roughdielectric"}


def test_rough_bsdfs_are_not_delta_and_flags(ctx, queue):
    """roughconductor is glossy, not delta; conductor, dielectric and thindielectric are delta, with zero eval and
    pdf (checked here beside it)."""
    f = flag_defines()
    assert row("roughconductor")["flags"] & f["BSDF_GLOSSY"] and not row("roughconductor")["flags"] & f["BSDF_DELTA"]
    for kind in ("conductor", "dielectric", "thindielectric"):
        assert row(kind)["flags"] & f["BSDF_DELTA"]
    wo = np.array([[0, 0, 1], [0, 0, -1], [0.6, 0, 0.8]])
    for kind in ("conductor", "dielectric", "thindielectric"):
        pdf, fv = bsdf_pdf_eval_batch(ctx, queue, row(kind), (0, 0, 1), wo)
        assert np.all(pdf == 0) and np.all(fv == 0)


# ---------------------------------------------------------------------------------------------- textures
def test_textured_parameters(ctx, queue):
    """A textured alpha reads the texture's first channel, a textured colour the texture: where the checkerboard
    shows value1 the BSDF equals the constant one with alpha 0.2 and colour value1, elsewhere 0.7 / value2; and one
    textured alpha of an anisotropic pair."""
    check_textured_like_constant(ctx, queue, "roughconductor", ("alpha", "specular_reflectance"),
                                 "specular_reflectance")
    rng = np.random.default_rng(4)
    wi = np.array([0.3, 0.2, 0.93])
    wo = rng.normal(size=(500, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    b = mitsuba_bsdf_with_checkers("roughconductor", ("alpha_u",), alpha_v=0.3, distribution="ggx")
    for uv, a in ((UV1, 0.2), (UV2, 0.7)):
        _, f1 = bsdf_pdf_eval_batch(ctx, queue, b.pack(), wi, wo, uv=uv, textures=b.textures_table)
        _, f2 = bsdf_pdf_eval_batch(ctx, queue, row("roughconductor", alpha_u=a, alpha_v=0.3, distribution="ggx"),
                                    wi, wo, uv=uv)
        np.testing.assert_allclose(f1, f2, rtol=1e-5, atol=1e-7)


# ------------------------------------------------------------------------------------------------ errors
@pytest.mark.parametrize("kind,kw,message", [
    ("roughconductor", dict(distribution="phong"), "distribution must be one of beckmann, ggx"),
    ("roughconductor", dict(alpha_u=0.1), "both alpha_u and alpha_v"),
    ("roughconductor", dict(roughness=0.1), "property 'roughness' is not used"),
])
def test_scene_errors(kind, kw, message):
    with pytest.raises(SceneError, match=message):
        make(kind, **kw)


# ------------------------------------------------------------------------------------------- render
@pytest.mark.plugin("roughconductor", "render")
# one render in the default run (each builds its own program: seconds), both with the slow suites
@pytest.mark.parametrize("dist", ["beckmann", pytest.param("ggx", marks=pytest.mark.slow)])
def test_furnace_render(ctx, queue, tmp_path, dist):
    """A roughconductor plane in a constant environment of radiance 1 (Mitsuba's path) shows its directional
    albedo, the quadrature of its eval (to 0.3 %) at the camera's direction."""
    xml = (f'<bsdf type="roughconductor"><string name="distribution" value="{dist}"/>'
           '<float name="alpha" value="0.3"/><string name="material" value="Cu"/></bsdf>')
    bsdf = make("roughconductor", distribution=dist, alpha=0.3, material="Cu")
    wi = furnace_wi()
    ref = albedo_quadrature(ctx, queue, bsdf.pack(), wi, specular_grid(bsdf, wi, (0.3,)))
    check_render_value(render_furnace_plane(tmp_path, xml), ref, rel_tol=3e-3)
