"""Mitsuba 3's principled BSDF (clrender/bsdfs/principled.py, kernels/bsdfs/principled.h) on the device: chi-square
of its sampling routine against its own pdf (diffuse, metallic, transmissive from either side and under total
internal reflection, clearcoat, anisotropic, smooth and rough, the sampling rates), the pdf's integral against the
fraction of samples that survive, weight == f cos / pdf and the events' eta, energy (white furnace) where the model
conserves it, eval, pdf and albedo against Mitsuba 3 itself (tests/mitsuba/bsdf_values/principled.json, written by
make_principled_values.py in that folder), textured parameters, a furnace render, and the scene errors.

All chi-square cases share one Šidák correction (N_CHI2 tests at overall level ALPHA).
"""
import numpy as np
import pytest

from clrender.device.dispatch import flag_defines
from clrender.errors import SceneError
from clrender.scene.properties import PropertyList
from clrender.scene.registry import create
from clrender.scene.spec import PluginSpec
from clrender.testing.directions import wi_at
from clrender.testing.plugin_checks import (ALPHA, FAMILIES, albedo_quadrature, bsdf_chi2, bsdf_sample_batch,
                                            check_pdf_integral, check_render_value, chi2_test, furnace_wi, mean_le,
                                            mitsuba_bsdf_with_checkers, render_furnace_plane, sidak)

from .principled_common import (check_albedo, check_eval_and_pdf, check_textured, check_weights, chi2_case_of,
                                grid_for, make, value_cases, values)

#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("principled", "twosided"), textures=("checkerboard_color",), levels=1)


CHI2_SEED = 11

# --------------------------------------------------------------------------------------- chi2 cases
CASES = {
    "diffuse-default-30": (dict(), wi_at(30)),
    "diffuse-rough-flat-80": (dict(roughness=1.0, flatness=0.5, sheen=1.0, base_color=(0.9, 0.4, 0.1)), wi_at(80)),
    "metal-smooth-60": (dict(metallic=1.0, roughness=0.25), wi_at(60)),
    "metal-rough-85": (dict(metallic=1.0, roughness=0.8), wi_at(85)),
    "glass-out-40": (dict(spec_trans=1.0, roughness=0.4, eta=1.5), wi_at(40)),
    "glass-in-30": (dict(spec_trans=1.0, roughness=0.4, eta=1.5), wi_at(30, -1)),
    "glass-in-60-tir": (dict(spec_trans=1.0, roughness=0.3, eta=1.5), wi_at(60, -1)),
    "half-glass-smooth-10": (dict(spec_trans=0.5, roughness=0.15, specular=0.5), wi_at(10)),
    "clearcoat-20": (dict(clearcoat=1.0, clearcoat_gloss=0.0, roughness=0.6, spec_trans=0.3), wi_at(20)),
    "clearcoat-glossy-50": (dict(clearcoat=1.0, clearcoat_gloss=0.5, metallic=0.5, roughness=0.5), wi_at(50)),
    "aniso-50": (dict(anisotropic=0.8, roughness=0.5, metallic=0.5), wi_at(50, phi_deg=35)),
    "rates-70": (dict(roughness=0.35, anisotropic=0.3, metallic=0.2, spec_trans=0.4, specular=0.7, clearcoat=0.5,
                      clearcoat_gloss=0.3, main_specular_sampling_rate=0.7, clearcoat_sampling_rate=2.0,
                      diffuse_reflectance_sampling_rate=0.5), wi_at(70, phi_deg=-20)),
}
N_CHI2 = FAMILIES["principled-chi2"]
# The default run samples a cross-section (every lobe, both sides, total internal reflection, the sampling rates);
# the rest is marked slow.
DEFAULT_CASES = {"diffuse-rough-flat-80", "metal-smooth-60", "glass-out-40", "glass-in-60-tir", "clearcoat-20",
                 "aniso-50", "rates-70"}
CASE_PARAMS = [pytest.param(c, marks=() if c in DEFAULT_CASES else pytest.mark.slow) for c in CASES]
chi2_case = chi2_case_of(CASES)


@pytest.mark.plugin("principled", "sampling")
@pytest.mark.parametrize("name", CASE_PARAMS)
def test_chi2_sample_vs_pdf(chi2_runs, name):
    chi2_runs.check(name)


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_pdf_integral_is_the_surviving_fraction(chi2_runs, name):
    """∫ pdf = P(a sample survives) <= 1: = 1 up to what visible normals scatter onto the wrong side of the surface;
    a binomial bound of 5 sigma plus the quadrature's 0.3%."""
    run = chi2_runs[name]
    kept = check_pdf_integral(run.total, run.keep, name)
    if name == "half-glass-smooth-10":   # smooth, near normal incidence: (almost) nothing may be lost
        assert kept > 0.995, f"{name}: kept {kept:.4f}"


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_weight_is_eval_cos_over_pdf(chi2_runs, name):
    check_weights(CASES, chi2_runs[name], name)


def test_chi2_rejects_wrong_pdfs(ctx, queue):
    """The test above can fail: samples scored against the pdf of a 10% different roughness, of other sampling
    rates, of another index of refraction."""
    for kw, other, wi in ((dict(metallic=1.0, roughness=0.5), dict(roughness=0.55), wi_at(30)),
                          (dict(clearcoat=1.0, roughness=0.5), dict(clearcoat_sampling_rate=1.3), wi_at(40)),
                          (dict(spec_trans=1.0, roughness=0.3, eta=1.5), dict(eta=1.6), wi_at(45, -1))):
        b = make(**kw)
        _, _, obs, exp = bsdf_chi2(ctx, queue, b.pack(), wi, grid_for(b, wi), seed=CHI2_SEED,
                                   pdf_row=make(**{**kw, **other}).pack())
        assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed, (kw, other)


# ------------------------------------------------------------------------------------ energy / furnace
FURNACE = [
    # a white metal: Schlick's F = 1, GGX single scattering loses the rest
    (dict(metallic=1.0, base_color=(1.0, 1.0, 1.0), roughness=r), th, 1) for r in (0.2, 0.6, 1.0)
    for th in (0, 60, 85)] + [
    # white rough glass: reflected plus transmitted importance (weight eta^2 for refractions), from either side
    (dict(spec_trans=1.0, base_color=(1.0, 1.0, 1.0), roughness=r, eta=1.5), th, side) for r in (0.3, 0.8)
    for th in (0, 50, 80) for side in (1, -1)]


def test_white_furnace(ctx, queue):
    """Energy <= 1 where the model conserves it: its metal and its glass. (Its diffuse base does not: Burley's
    diffuse, retro-reflection, sheen and clearcoat are added to the specular lobe, not weighted against it; a white
    base returns up to 1.31 of what arrives, in Mitsuba as here: test_albedo_matches_mitsuba, cases white-*.)"""
    a_t = sidak(ALPHA, FAMILIES["principled-furnace"])
    for kw, th, side in FURNACE:
        b = make(**kw)
        wi = wi_at(th, side)
        s = bsdf_sample_batch(ctx, queue, b.pack(), wi, 100000, 41)
        w = s.weight[:, 0].astype(np.float64) * s.eta.astype(np.float64) ** 2
        assert mean_le(w, 1.0, a_t), f"{kw} at {th} deg ({side}): albedo {w.mean():.5f}"
        if kw.get("roughness") == 0.2 and th == 0:
            assert w.mean() > 0.97, "a smooth white metal at normal incidence loses almost nothing"
        if kw.get("roughness") == 0.3 and th == 0:
            assert w.mean() > 0.97, "a smooth white glass at normal incidence loses almost nothing"


# ----------------------------------------------------------------------------------- against Mitsuba
@pytest.mark.plugin("principled", "eval")
@pytest.mark.parametrize("name", value_cases("principled.json"))
def test_eval_and_pdf_match_mitsuba(ctx, queue, name):
    check_eval_and_pdf(ctx, queue, "principled.json", name)


@pytest.mark.parametrize("name", value_cases("principled.json"))
def test_albedo_matches_mitsuba(ctx, queue, name):
    check_albedo(ctx, queue, "principled.json", name)


def test_reference_file_is_mitsubas():
    v = values()
    assert v["mitsuba_version"].startswith("3.9")
    assert {c["variant"] for c in v["cases"].values()} == {"scalar_rgb", "llvm_ad_rgb"}
    assert len(v["cases"]) >= 16 and len(v["wi"]) == len(v["wo"]) >= 250
    assert max(c["albedo"][2][0] for c in v["cases"].values()) > 1.2, "Mitsuba's white base gains energy"


# ---------------------------------------------------------------------------------------------- textures
def test_textured_parameters(ctx, queue):
    check_textured(ctx, queue, "principled", ("base_color", "roughness", "anisotropic", "metallic", "spec_trans",
                                              "spec_tint", "sheen", "sheen_tint", "flatness", "clearcoat",
                                              "clearcoat_gloss"))


def test_flags_and_defaults():
    f = flag_defines()
    r = make().pack()
    assert r["flags"] & f["BSDF_GLOSSY"] and r["flags"] & f["BSDF_DIFFUSE"] and not r["flags"] & f["BSDF_DELTA"]
    assert not r["flags"] & f["BSDF_UV"]
    b = make()
    assert b.floats["roughness"][0] == 0.5 and np.allclose(b.base_color[0], 0.5)
    assert b.rates == {"spec_srate": 1.0, "clearcoat_srate": 1.0, "diffuse_srate": 1.0}
    assert np.isclose(b.eta, 2 / (1 - np.sqrt(0.04)) - 1)            # specular 0.5
    # Mitsuba's special cases with a transmitting lobe
    assert make(spec_trans=0.5, eta=1.0).eta == pytest.approx(1.001)
    assert make(eta=1.0).eta == 1.0
    assert make(spec_trans=0.5, specular=0.0).eta == pytest.approx(2 / (1 - np.sqrt(0.08e-3)) - 1, rel=1e-6)
    assert make(anisotropic=0.3).pack()["flags"] & f["BSDF_UV"]


# ------------------------------------------------------------------------------------------- render
@pytest.mark.plugin("principled", "render")
@pytest.mark.slow   # its program alone takes 15-25 s to build: run with the slow suites
def test_furnace_render(ctx, queue, tmp_path):
    """A principled plane (a rough half-metal with a clearcoat and some transmission) in a constant environment of
    radiance 1 (Mitsuba's path) shows its directional albedo, the quadrature of its eval (to 0.3 %) at the camera's
    direction."""
    kw = dict(metallic=0.5, roughness=0.5, clearcoat=0.5, spec_trans=0.3)
    xml = '<bsdf type="principled">' + "".join(f'<float name="{k}" value="{v}"/>' for k, v in kw.items()) + "</bsdf>"
    b = make(**kw)
    wi = furnace_wi()
    ref = albedo_quadrature(ctx, queue, b.pack(), wi, grid_for(b, wi))
    check_render_value(render_furnace_plane(tmp_path, xml), ref, rel_tol=3e-3)


# ------------------------------------------------------------------------------------------------ errors
@pytest.mark.parametrize("kw,message", [
    (dict(eta=1.5, specular=0.5), "either eta or specular"),
    (dict(specular=13.0), r"specular must be in \[0, 12.5\)"),
    (dict(eta=-1.0), "eta must be positive"),
    (dict(base_color=(-0.1, 0.5, 0.5)), "base_color must be non-negative"),
    (dict(clearcoat_sampling_rate=-1.0), "clearcoat_sampling_rate must be non-negative"),
    (dict(subsurface=0.5), "property 'subsurface' is not used"),
])
def test_scene_errors(kw, message):
    with pytest.raises(SceneError, match=message):
        make(**kw)


def test_error_names_the_file_and_line(tmp_path):
    from clrender import load_scene

    xml = tmp_path / "s.xml"
    xml.write_text('<scene version="3.0.0">\n  <shape type="sphere">\n    <bsdf type="principled">\n'
                   '      <float name="eta" value="1.4"/>\n      <float name="specular" value="0.3"/>\n'
                   '    </bsdf>\n  </shape>\n</scene>\n')
    with pytest.raises(SceneError) as e:
        load_scene(xml)
    assert "s.xml" in str(e.value) and ":5" in str(e.value) and "either eta or specular" in str(e.value)


# twosided(child) in Mitsuba 3.9.1 (scalar_rgb, load_dict): refused exactly where the child's flags hold Transmission.
# principledthin always (checked here beside principled); principled when spec_trans is given and not the float 0 (a
# texture counts as given).
@pytest.mark.parametrize("kind,params,transmits", [
    ("principledthin", {}, True),
    ("principledthin", {"spec_trans": 0.0, "diff_trans": 0.0}, True),
    ("principled", {}, False),
    ("principled", {"spec_trans": 0.0, "metallic": 0.5}, False),
    ("principled", {"spec_trans": 0.5}, True),
    ("principled", {"spec_trans": "texture"}, True),
])
def test_twosided_refuses_exactly_the_transmitting_ones(kind, params, transmits):
    floats = {k: v for k, v in params.items() if v != "texture"}
    textured = [k for k, v in params.items() if v == "texture"]
    child = mitsuba_bsdf_with_checkers(kind, textured, **floats) if textured else make(kind, **floats)
    assert bool(child.pack()["flags"] & flag_defines()["BSDF_TRANSMISSION"]) == transmits
    assert ("TRANSMISSION" in child.capabilities()) == transmits
    spec = child.spec
    two = PluginSpec("bsdf", "twosided", None, PropertyList('<bsdf type="twosided">', fmt="mitsuba"), [spec], None,
                     format="mitsuba")
    if transmits:
        with pytest.raises(SceneError, match=f'nested <bsdf type="{kind}"> transmits light'):
            create(two)
    else:
        assert create(two).capabilities() == {"GLOSSY", "DIFFUSE"}
