"""Mitsuba 3's principledthin BSDF (a thin sheet: clrender/bsdfs/principledthin.py, kernels/bsdfs/principledthin.h)
on the device: chi-square of its sampling routine against its own pdf (from either side, smooth and rough, the
sampling rates), the pdf's integral against the fraction of samples that survive, weight == f cos / pdf and the
events' eta, energy (white furnace), eval, pdf and albedo against Mitsuba 3 itself (tests/mitsuba/bsdf_values/
principledthin.json, written by make_principled_values.py in that folder), textured parameters, a furnace render,
and the scene errors.

All chi-square cases share one Šidák correction (N_CHI2 tests at overall level ALPHA).
"""
import numpy as np
import pytest

from clrender.device.dispatch import flag_defines
from clrender.errors import SceneError
from clrender.testing.directions import wi_at
from clrender.testing.plugin_checks import (ALPHA, FAMILIES, albedo_quadrature, bsdf_chi2, bsdf_sample_batch,
                                            check_pdf_integral, check_render_value, chi2_test, furnace_wi, mean_le,
                                            render_furnace_plane, sidak)

from .principled_common import (check_albedo, check_eval_and_pdf, check_textured, check_weights, chi2_case_of,
                                grid_for, make, value_cases)

#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("principledthin",), textures=("checkerboard_color",))


CHI2_SEED = 11

# --------------------------------------------------------------------------------------- chi2 cases
CASES = {
    "thin-doc-40": (dict(kind="principledthin", base_color=(0.7, 0.1, 0.1), roughness=0.15, spec_tint=0.1,
                         anisotropic=0.5, spec_trans=0.8, diff_trans=0.3, eta=1.33), wi_at(40, phi_deg=20)),
    "thin-back-60": (dict(kind="principledthin", roughness=0.4, spec_trans=0.5, diff_trans=0.8), wi_at(60, -1)),
    "thin-leaf-75": (dict(kind="principledthin", roughness=0.6, spec_trans=0.2, diff_trans=1.2, sheen=0.5,
                          flatness=0.4, eta=1.4), wi_at(75)),
    "thin-smooth-rates-20": (dict(kind="principledthin", roughness=0.15, spec_trans=0.6, diff_trans=0.5,
                                  specular_reflectance_sampling_rate=2.0, specular_transmittance_sampling_rate=0.5,
                                  diffuse_reflectance_sampling_rate=0.7, diffuse_transmittance_sampling_rate=1.5),
                             wi_at(20)),
}
N_CHI2 = FAMILIES["principled-chi2"]
# The default run samples one (the back side, the transmission lobes); the rest is marked slow.
DEFAULT_CASES = {"thin-back-60"}
CASE_PARAMS = [pytest.param(c, marks=() if c in DEFAULT_CASES else pytest.mark.slow) for c in CASES]
chi2_case = chi2_case_of(CASES)


@pytest.mark.plugin("principledthin", "sampling")
@pytest.mark.parametrize("name", CASE_PARAMS)
def test_chi2_sample_vs_pdf(chi2_runs, name):
    chi2_runs.check(name)


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_pdf_integral_is_the_surviving_fraction(chi2_runs, name):
    """∫ pdf = P(a sample survives) <= 1; a binomial bound of 5 sigma plus the quadrature's 0.3%."""
    run = chi2_runs[name]
    check_pdf_integral(run.total, run.keep, name)


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_weight_is_eval_cos_over_pdf(chi2_runs, name):
    check_weights(CASES, chi2_runs[name], name)


def test_chi2_rejects_wrong_pdfs(ctx, queue):
    """The test above can fail: samples scored against the pdf of another index of refraction (the transmission's
    roughness) and of another sampling rate."""
    for kw, other, wi in ((dict(kind="principledthin", spec_trans=1.0, roughness=0.5, eta=1.5), dict(eta=1.7),
                           wi_at(30)),
                          (dict(kind="principledthin", spec_trans=0.5, diff_trans=1.0),
                           dict(diffuse_transmittance_sampling_rate=1.3), wi_at(30, -1))):
        b = make(**kw)
        _, _, obs, exp = bsdf_chi2(ctx, queue, b.pack(), wi, grid_for(b, wi), seed=CHI2_SEED,
                                   pdf_row=make(**{**kw, **other}).pack())
        assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed, (kw, other)


# ------------------------------------------------------------------------------------ energy / furnace
FURNACE = [  # a white thin sheet's specular reflection and transmission
    (dict(kind="principledthin", spec_trans=1.0, base_color=(1.0, 1.0, 1.0), roughness=r, eta=1.5), th, 1)
    for r in (0.3, 0.8) for th in (0, 50, 80)]


def test_white_furnace(ctx, queue):
    """A white sheet's specular reflection and transmission return at most what arrives; a white sheet of pure
    diffuse transmission passes everything, exactly."""
    a_t = sidak(ALPHA, FAMILIES["principled-furnace"])
    for kw, th, side in FURNACE:
        b = make(**kw)
        wi = wi_at(th, side)
        s = bsdf_sample_batch(ctx, queue, b.pack(), wi, 100000, 41)
        w = s.weight[:, 0].astype(np.float64) * s.eta.astype(np.float64) ** 2
        assert mean_le(w, 1.0, a_t), f"{kw} at {th} deg ({side}): albedo {w.mean():.5f}"
        if kw.get("roughness") == 0.3 and th == 0:
            assert w.mean() > 0.97, "a smooth white sheet at normal incidence loses almost nothing"
    s = bsdf_sample_batch(ctx, queue, make("principledthin", base_color=(1.0, 1.0, 1.0), diff_trans=2.0).pack(),
                          wi_at(35, -1), 1000, 3)
    np.testing.assert_allclose(s.weight, 1.0, rtol=1e-5)
    assert np.all(s.wo[:, 2] > 0)


# ----------------------------------------------------------------------------------- against Mitsuba
@pytest.mark.plugin("principledthin", "eval")
@pytest.mark.parametrize("name", value_cases("principledthin.json"))
def test_eval_and_pdf_match_mitsuba(ctx, queue, name):
    check_eval_and_pdf(ctx, queue, "principledthin.json", name)


@pytest.mark.parametrize("name", value_cases("principledthin.json"))
def test_albedo_matches_mitsuba(ctx, queue, name):
    check_albedo(ctx, queue, "principledthin.json", name)


def test_textured_parameters(ctx, queue):
    check_textured(ctx, queue, "principledthin", ("base_color", "roughness", "anisotropic", "spec_trans",
                                                  "spec_tint", "sheen", "sheen_tint", "flatness", "diff_trans", "eta"))


def test_flags_and_defaults():
    f = flag_defines()
    t = make("principledthin")
    assert t.floats["eta"][0] == 1.5 and t.floats["roughness"][0] == 0.5 and t.floats["diff_trans"][0] == 0
    assert set(t.rates.values()) == {1.0} and len(t.rates) == 4
    r = t.pack()
    assert r["flags"] & f["BSDF_GLOSSY"] and r["flags"] & f["BSDF_DIFFUSE"] and not r["flags"] & f["BSDF_UV"]


# ------------------------------------------------------------------------------------------- render
@pytest.mark.plugin("principledthin", "render")
@pytest.mark.slow   # its program alone takes 15-25 s to build: run with the slow suites
def test_furnace_render(ctx, queue, tmp_path):
    """A principledthin plane (a leaf: rough, transmitting both ways) in a constant environment of radiance 1
    (Mitsuba's path) shows its directional albedo, the quadrature of its eval (to 0.3 %) at the camera's
    direction."""
    kw = dict(roughness=0.4, spec_trans=0.5, diff_trans=0.8)
    xml = '<bsdf type="principledthin">' + "".join(f'<float name="{k}" value="{v}"/>' for k, v in kw.items()) + \
          "</bsdf>"
    b = make("principledthin", **kw)
    wi = furnace_wi()
    ref = albedo_quadrature(ctx, queue, b.pack(), wi, grid_for(b, wi))
    check_render_value(render_furnace_plane(tmp_path, xml), ref, rel_tol=3e-3)


# ------------------------------------------------------------------------------------------------ errors
@pytest.mark.parametrize("kw,message", [
    (dict(kind="principledthin", eta=0.0), "eta must be positive"),
    (dict(kind="principledthin", specular=0.5), "property 'specular' is not used"),
    (dict(kind="principledthin", diffuse_transmittance_sampling_rate=-2.0), "must be non-negative"),
])
def test_scene_errors(kw, message):
    with pytest.raises(SceneError, match=message):
        make(**kw)
