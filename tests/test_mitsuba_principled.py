"""Mitsuba 3's principled and principledthin BSDFs on the device (kernels/bsdfs/principled.h, principledthin.h):
chi-square of the sampling routines against their own pdfs (diffuse, metallic, transmissive from either side and
under total internal reflection, clearcoat, anisotropic, smooth and rough, the sampling rates; thin sheets from
either side), the pdf's integral against the fraction of samples that survive, weight == f cos / pdf and the events'
eta, energy (white furnace) where the models conserve it, eval, pdf and albedo against Mitsuba 3 itself
(tests/mitsuba/bsdf_values/principled.json and principledthin.json, written by make_principled_values.py in that
folder), textured parameters, and the scene errors.

All chi-square cases share one Šidák correction (N_CHI2 tests at overall level ALPHA).
"""
import functools
import json
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from clrender import plugins  # noqa: F401  (registers the plugins)
from clrender.device import layout
from clrender.device.dispatch import flag_defines
from clrender.errors import SceneError
from clrender.scene.properties import PropertyList
from clrender.scene.registry import create
from clrender.scene.spec import PluginSpec
from clrender.testing.chi2 import (bin_directions, check_pdf_integral, check_sample_weights, chi2_test,
                                   expected_from_grid, refined_direction_grid, sidak)
from clrender.testing.directions import refracted, wi_at
from clrender.testing.kernels import bsdf_pdf_eval_batch, bsdf_sample_batch
from clrender.testing.mitsuba_dict import spec_from_dict
from clrender.textures.texture import TextureTable

ALPHA = 0.01
RES = 10
N_SAMPLES = 5000 * RES * RES
SUB = 8
VALUES = Path(__file__).resolve().parent / "mitsuba" / "bsdf_values"
VALUE_FILES = ("principled.json", "principledthin.json")


def make(kind="principled", **kw):
    """The plugin as a Mitsuba file (here: a Mitsuba dict) gives it; colours are tuples."""
    d = {"type": kind}
    for k, v in kw.items():
        d[k] = {"type": "rgb", "value": list(v)} if isinstance(v, tuple) else v
    return create(spec_from_dict(d))


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
    # principledthin
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
N_CHI2 = len(CASES)
# The default run samples a cross-section (every lobe, both sides, total internal reflection, the sampling rates);
# the rest is marked slow.
DEFAULT_CASES = {"diffuse-rough-flat-80", "metal-smooth-60", "glass-out-40", "glass-in-60-tir", "clearcoat-20",
                 "aniso-50", "rates-70", "thin-back-60"}
CASE_PARAMS = [pytest.param(c, marks=() if c in DEFAULT_CASES else pytest.mark.slow) for c in CASES]


def _alphas(b):
    """The roughnesses of the lobes, for refining the integration grid around their peaks."""
    out = []
    r = b.floats["roughness"][0]
    aspect = np.sqrt(1 - 0.9 * b.floats["anisotropic"][0])
    thin = "diff_trans" in b.floats
    for s in ((1.0, 0.65 * b.floats["eta"][0] - 0.35) if thin else (1.0,)):
        r2 = (s * r) ** 2
        out += [max(1e-3, r2 / aspect), max(1e-3, r2 * aspect)]
    if b.floats.get("clearcoat", (0,))[0] > 0:
        out.append(0.1 + b.floats["clearcoat_gloss"][0] * (0.001 - 0.1))
    return out


def transmits(b):
    return b.floats["spec_trans"][0] > 0 or b.floats.get("diff_trans", (0,))[0] > 0


def _grid_for(b, wi):
    """Integration points refined around the peaks (the mirror direction and the refracted one) at the lobes'
    widths and their widths across the plane of incidence."""
    peaks = []
    targets = [wi * np.array([-1, -1, 1])]
    t = -wi if "diff_trans" in b.floats else refracted(wi, b.eta)   # a thin sheet does not bend light
    if t is not None and transmits(b):
        targets.append(t)
    for a in _alphas(b):
        if a >= 0.6:
            continue
        for d in targets:
            peaks += [(d, min(14 * a, np.pi)), (d, 14 * a * max(abs(wi[2]), 0.03)), (d, 1.2 * a)]
    return refined_direction_grid(RES, SUB, peaks, n_fine=300)


def run_chi2(ctx, queue, b, wi, n=N_SAMPLES, seed=11, pdf_row=None):
    s = bsdf_sample_batch(ctx, queue, b.pack(), wi, n, seed)
    keep = np.any(s.weight != 0, axis=1)
    obs = bin_directions(s.wo[keep], RES)
    dirs, w, cell = _grid_for(b, wi)
    pdf, _ = bsdf_pdf_eval_batch(ctx, queue, b.pack() if pdf_row is None else pdf_row, wi, dirs)
    return s, keep, obs, expected_from_grid(pdf, w, cell, (RES, 2 * RES), n)


class _Runs(dict):
    def __init__(self, ctx, queue):
        super().__init__()
        self.ctx, self.queue = ctx, queue

    def __missing__(self, name):
        kw, wi = CASES[name]
        b = make(**kw)
        s, keep, obs, exp = run_chi2(self.ctx, self.queue, b, wi)
        self[name] = (b, s, keep, chi2_test(obs, exp, min_exp=5.0, alpha=ALPHA, n_tests=N_CHI2), exp.sum(), wi)
        return self[name]


@pytest.fixture(scope="module")
def chi2_runs(ctx, queue):
    return _Runs(ctx, queue)


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_chi2_sample_vs_pdf(chi2_runs, name):
    b, s, keep, res, total, wi = chi2_runs[name]
    assert res.passed, f"{name}: {res.message}"


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_pdf_integral_is_the_surviving_fraction(chi2_runs, name):
    """∫ pdf = P(a sample survives) <= 1: = 1 up to what visible normals scatter onto the wrong side of the surface;
    a binomial bound of 5 sigma plus the quadrature's 0.3%."""
    b, s, keep, res, total, wi = chi2_runs[name]
    kept = check_pdf_integral(total, keep, name)
    if name == "half-glass-smooth-10":   # smooth, near normal incidence: (almost) nothing may be lost
        assert kept > 0.995, f"{name}: kept {kept:.4f}"


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_weight_is_eval_cos_over_pdf(chi2_runs, name):
    b, s, keep, res, total, wi = chi2_runs[name]
    refl = check_sample_weights(s, keep, wi)
    if transmits(b):
        assert (~refl).any(), f"{name}: no transmission sampled"
        eta = 1.0 if "diff_trans" in b.floats else b.eta if wi[2] > 0 else 1 / b.eta   # thin: no refraction
        np.testing.assert_allclose(s.eta[keep][~refl], eta, rtol=1e-6)
    else:
        assert refl.all()


def test_chi2_rejects_wrong_pdfs(ctx, queue):
    """The test above can fail: samples scored against the pdf of a 10% different roughness, of other sampling
    rates, of another index of refraction (principled: refraction; principledthin: the transmission's roughness)."""
    for kw, other, wi in ((dict(metallic=1.0, roughness=0.5), dict(roughness=0.55), wi_at(30)),
                          (dict(clearcoat=1.0, roughness=0.5), dict(clearcoat_sampling_rate=1.3), wi_at(40)),
                          (dict(spec_trans=1.0, roughness=0.3, eta=1.5), dict(eta=1.6), wi_at(45, -1)),
                          (dict(kind="principledthin", spec_trans=1.0, roughness=0.5, eta=1.5), dict(eta=1.7),
                           wi_at(30)),
                          (dict(kind="principledthin", spec_trans=0.5, diff_trans=1.0),
                           dict(diffuse_transmittance_sampling_rate=1.3), wi_at(30, -1))):
        b = make(**kw)
        _, _, obs, exp = run_chi2(ctx, queue, b, wi, pdf_row=make(**{**kw, **other}).pack())
        assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed, (kw, other)


# ------------------------------------------------------------------------------------ energy / furnace
def mean_le(w, bound, a):
    """The mean of w is not significantly above bound (one-sided t-test at level a)."""
    w = np.asarray(w, np.float64)
    return w.mean() <= bound or stats.ttest_1samp(w, bound, alternative="greater").pvalue > a


FURNACE = [
    # a white metal: Schlick's F = 1, GGX single scattering loses the rest
    (dict(metallic=1.0, base_color=(1.0, 1.0, 1.0), roughness=r), th, 1) for r in (0.2, 0.6, 1.0)
    for th in (0, 60, 85)] + [
    # white rough glass: reflected plus transmitted importance (weight eta^2 for refractions), from either side
    (dict(spec_trans=1.0, base_color=(1.0, 1.0, 1.0), roughness=r, eta=1.5), th, side) for r in (0.3, 0.8)
    for th in (0, 50, 80) for side in (1, -1)] + [
    # a white thin sheet's specular reflection and transmission
    (dict(kind="principledthin", spec_trans=1.0, base_color=(1.0, 1.0, 1.0), roughness=r, eta=1.5), th, 1)
    for r in (0.3, 0.8) for th in (0, 50, 80)]


def test_white_furnace(ctx, queue):
    """Energy <= 1 where the model conserves it: its metal and its glass. (Its diffuse base does not: Burley's
    diffuse, retro-reflection, sheen and clearcoat are added to the specular lobe, not weighted against it; a white
    base returns up to 1.31 of what arrives, in Mitsuba as here: test_albedo_matches_mitsuba, cases white-*.)"""
    a_t = sidak(ALPHA, len(FURNACE))
    for kw, th, side in FURNACE:
        b = make(**kw)
        wi = wi_at(th, side)
        s = bsdf_sample_batch(ctx, queue, b.pack(), wi, 100000, 41)
        w = s.weight[:, 0].astype(np.float64) * s.eta.astype(np.float64) ** 2
        assert mean_le(w, 1.0, a_t), f"{kw} at {th} deg ({side}): albedo {w.mean():.5f}"
        if kw.get("roughness") == 0.2 and th == 0:
            assert w.mean() > 0.97, "a smooth white metal at normal incidence loses almost nothing"
        if kw.get("roughness") == 0.3 and th == 0:
            assert w.mean() > 0.97, "a smooth white glass or sheet at normal incidence loses almost nothing"
    # a white sheet of pure diffuse transmission passes everything, exactly
    s = bsdf_sample_batch(ctx, queue, make("principledthin", base_color=(1.0, 1.0, 1.0), diff_trans=2.0).pack(),
                          wi_at(35, -1), 1000, 3)
    np.testing.assert_allclose(s.weight, 1.0, rtol=1e-5)
    assert np.all(s.wo[:, 2] > 0)


# ----------------------------------------------------------------------------------- against Mitsuba
@functools.lru_cache(maxsize=None)
def _values(fname="principled.json"):
    return json.loads((VALUES / fname).read_text())


def _value_cases():
    return [pytest.param(f, name, id=name) for f in VALUE_FILES for name in _values(f)["cases"]]


def rows_of(d):
    b = create(spec_from_dict(d))
    table = TextureTable()
    return np.array(b.pack_rows(table), layout.dtype("Bsdf")), table.array()


@pytest.mark.parametrize("fname,name", _value_cases())
def test_eval_and_pdf_match_mitsuba(ctx, queue, fname, name):
    """Mitsuba's eval (f |cos_o|) and pdf at 292 direction pairs per case. float32 against Mitsuba's float32 in
    another order of operations: the largest difference measured is 2.6e-4 relative for principled (GGX alpha
    0.0025 and GTR1 alpha 0.011, where D changes fastest), 1.2e-6 for principledthin; 2e-3 leaves room for
    compilers, and is far below what a wrong term makes (the weakest lobe here, sheen at spec_trans 1, shifts
    values by 0.02-2 %)."""
    data = _values(fname)
    case = data["cases"][name]
    wi, wo = np.array(data["wi"]), np.array(data["wo"])
    rows, tex = rows_of(case["dict"])
    pdf, f = bsdf_pdf_eval_batch(ctx, queue, rows, wi, wo, textures=tex)
    got, ref, ref_pdf = f * np.abs(wo[:, 2:3]), np.array(case["eval"]), np.array(case["pdf"])
    assert (ref > 0).any(1).sum() > 80, "the reference set must exercise the lobes"
    close = np.abs(got - ref) <= 1e-7 + 2e-3 * np.abs(ref)
    bad = np.nonzero(~close.all(1))[0]
    assert close.all(), f"eval differs from Mitsuba's at pairs {bad.tolist()}: {got[bad][:3].tolist()} vs " \
                        f"{ref[bad][:3].tolist()}"
    close = np.abs(pdf - ref_pdf) <= 1e-7 + 2e-3 * np.abs(ref_pdf)
    bad = np.nonzero(~close)[0]
    assert close.all(), f"pdf differs from Mitsuba's at pairs {bad.tolist()}: {pdf[bad][:3]} vs {ref_pdf[bad][:3]}"


@pytest.mark.parametrize("fname,name", _value_cases())
def test_albedo_matches_mitsuba(ctx, queue, fname, name):
    """The mean sample weight (the albedo, radiance transport) at four incident directions against Mitsuba's own
    sample() over 2^18 samples: a z-test of the difference against both standard errors, Šidák-corrected over all
    cases and directions. This checks the sampling routine's weights as a whole, where eval and pdf check its
    parts."""
    data = _values(fname)
    case = data["cases"][name]
    rows, tex = rows_of(case["dict"])
    n = 1 << 17
    a_t = sidak(ALPHA, 4 * sum(len(_values(f)["cases"]) for f in VALUE_FILES))
    for (th, side), (ref, ref_se) in zip(data["albedo_wi"], case["albedo"]):
        s = bsdf_sample_batch(ctx, queue, rows, wi_at(th, side), n, 29, textures=tex)
        w = s.weight[:, 0].astype(np.float64)
        se = np.hypot(w.std() / np.sqrt(n), ref_se)
        if se < 1e-6:   # a constant weight (a Lambertian lobe alone, or nothing)
            assert abs(w.mean() - ref) <= 1e-5 * max(1.0, abs(ref)), f"{name} at {th} deg ({side}): {w.mean()} vs {ref}"
            continue
        p = 2 * stats.norm.sf(abs(w.mean() - ref) / se)
        assert p > a_t, f"{name} at {th} deg ({side}): albedo {w.mean():.5f} vs Mitsuba's {ref:.5f} +- {ref_se:.5f}"


def test_reference_file_is_mitsubas():
    v = _values()
    assert v["mitsuba_version"].startswith("3.9")
    assert {c["variant"] for c in v["cases"].values()} == {"scalar_rgb", "llvm_ad_rgb"}
    assert len(v["cases"]) >= 16 and len(v["wi"]) == len(v["wo"]) >= 250
    assert max(c["albedo"][2][0] for c in v["cases"].values()) > 1.2, "Mitsuba's white base gains energy"


# ---------------------------------------------------------------------------------------------- textures
def _with_textures(names, kind="principled", **kw):
    """The BSDF with Nori checkerboard textures nested under `names` (any texture plugin does)."""
    kids = []
    for name in names:
        tp = PropertyList('<texture type="checkerboard_color">')
        tp.add("value1", "color", (0.2, 0.4, 0.6))
        tp.add("value2", "color", (0.7, 0.5, 0.3))
        kids.append(PluginSpec("texture", "checkerboard_color", name, tp, [], None, format="nori"))
    pl = PropertyList(f'<bsdf type="{kind}">', fmt="mitsuba")
    for k, v in kw.items():
        pl.add(k, "float", float(v))
    return create(PluginSpec("bsdf", kind, None, pl, kids, None, format="mitsuba"))


TEXTURABLE = [("principled", n) for n in ("base_color", "roughness", "anisotropic", "metallic", "spec_trans",
                                          "spec_tint", "sheen", "sheen_tint", "flatness", "clearcoat",
                                          "clearcoat_gloss")] + \
             [("principledthin", n) for n in ("base_color", "roughness", "anisotropic", "spec_trans", "spec_tint",
                                              "sheen", "sheen_tint", "flatness", "diff_trans", "eta")]


def test_textured_parameters(ctx, queue):
    """Every texturable parameter, textured, equals the constant BSDF with the texture's value there: a float reads
    the texture's first channel (0.2 where the checkerboard shows value1, 0.7 elsewhere), base_color the colour."""
    rng = np.random.default_rng(4)
    wi = np.array([0.3, 0.2, 0.93])
    wo = rng.normal(size=(600, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    uv1, uv2 = (0.1, 0.1), (0.6, 0.1)
    for kind, name in TEXTURABLE:
        # the lobes the parameter modulates are on
        extra = dict(spec_trans=0.4) if name != "spec_trans" else {}
        if name == "sheen_tint":
            extra["sheen"] = 0.8
        if name == "clearcoat_gloss":
            extra["clearcoat"] = 1.0
        if name == "spec_tint" and kind == "principled":
            extra["metallic"] = 0.2
        if kind == "principledthin" and name != "diff_trans":
            extra["diff_trans"] = 0.5
        b = _with_textures((name,), kind, **extra)
        r = b.pack()
        assert r["flags"] & flag_defines()["BSDF_UV"]
        for uv, v, c in ((uv1, 0.2, (0.2, 0.4, 0.6)), (uv2, 0.7, (0.7, 0.5, 0.3))):
            ref = make(kind, **extra, **{name: c if name == "base_color" else v}).pack()
            p1, f1 = bsdf_pdf_eval_batch(ctx, queue, r, wi, wo, uv=uv, textures=b.textures_table)
            p2, f2 = bsdf_pdf_eval_batch(ctx, queue, ref, wi, wo, uv=uv)
            assert f2.max() > 0
            np.testing.assert_allclose(f1, f2, rtol=1e-5, atol=1e-7, err_msg=f"{kind} {name}")
            np.testing.assert_allclose(p1, p2, rtol=1e-5, atol=1e-7, err_msg=f"{kind} {name}")


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
    t = make("principledthin")
    assert t.floats["eta"][0] == 1.5 and t.floats["roughness"][0] == 0.5 and t.floats["diff_trans"][0] == 0
    assert set(t.rates.values()) == {1.0} and len(t.rates) == 4
    r = t.pack()
    assert r["flags"] & f["BSDF_GLOSSY"] and r["flags"] & f["BSDF_DIFFUSE"] and not r["flags"] & f["BSDF_UV"]


# ------------------------------------------------------------------------------------------------ errors
@pytest.mark.parametrize("kw,message", [
    (dict(kind="principledthin", eta=0.0), "eta must be positive"),
    (dict(kind="principledthin", specular=0.5), "property 'specular' is not used"),
    (dict(kind="principledthin", diffuse_transmittance_sampling_rate=-2.0), "must be non-negative"),
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
# principledthin always; principled when spec_trans is given and not the float 0 (a texture counts as given).
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
    child = _with_textures(textured, kind, **floats) if textured else make(kind, **floats)
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
