"""Mitsuba 3's conductors and dielectrics on the device (kernels/bsdfs/{conductor,roughconductor,dielectric,
thindielectric,roughdielectric}.h): chi-square of every sampling routine against its own pdf (Beckmann and GGX,
isotropic and anisotropic, visible normals or not, from outside and inside, grazing, total internal reflection),
the pdf's integral against the fraction of samples that survive, weight == f cos / pdf, energy (white furnace) and
reciprocity, values against Mitsuba 3 itself (tests/mitsuba/bsdf_values, written by make_bsdf_values.py), the
delta BSDFs' events, textures, and the scene errors.

All chi-square cases share one Šidák correction (N_CHI2 tests at overall level ALPHA).
"""
import functools
import json
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from clrender import plugins  # noqa: F401  (registers the plugins)
from clrender.bsdfs.conductor import MATERIALS
from clrender.bsdfs.ior import NAMED_IORS, lookup_ior
from clrender.device.dispatch import flag_defines
from clrender.errors import SceneError
from clrender.scene.properties import PropertyList
from clrender.scene.registry import create, instantiate
from clrender.scene.spec import PluginSpec
from clrender.testing.chi2 import (bin_directions, check_pdf_integral, check_sample_weights, chi2_test,
                                   expected_from_grid, refined_direction_grid, sidak)
from clrender.testing.kernels import bsdf_pdf_eval_batch, bsdf_sample_batch

ALPHA = 0.01
RES = 10
N_SAMPLES = 5000 * RES * RES
SUB = 8
VALUES = Path(__file__).parent / "mitsuba" / "bsdf_values" / "conductors_dielectrics.json"


# ------------------------------------------------------------------------------------------- rows
def _props(**kw):
    out = {}
    for k, v in kw.items():
        if isinstance(v, str):
            out[k] = ("string", v)
        elif isinstance(v, bool):
            out[k] = ("boolean", v)
        elif isinstance(v, tuple):
            out[k] = ("color", v)
        else:
            out[k] = ("float", float(v))
    return out


def make(kind, props=None, **kw):
    """The plugin as a Mitsuba file would give it (rows are always built by the plugins themselves)."""
    return instantiate("bsdf", kind, props if props is not None else _props(**kw), fmt="mitsuba")


def row(kind, **kw):
    return make(kind, **kw).pack()


def wi_at(theta_deg, side=1):
    t = np.radians(theta_deg)
    return np.array([np.sin(t), 0.0, side * np.cos(t)])


def refracted(wi, eta_ext, eta_int):
    """The macro-surface refraction direction of wi (None under total internal reflection)."""
    ei, et = (eta_ext, eta_int) if wi[2] > 0 else (eta_int, eta_ext)
    r = ei / et
    s2 = r * r * (1 - wi[2] ** 2)
    if s2 >= 1:
        return None
    return np.array([-r * wi[0], -r * wi[1], -np.sign(wi[2]) * np.sqrt(1 - s2)])


# --------------------------------------------------------------------------------------- chi2 cases
def _cases():
    cases = []
    for dist in ("beckmann", "ggx"):
        for a in (0.05, 0.3, 0.8):
            for th in (0.0, 45.0, 80.0, 88.0):
                cases.append((f"rc-{dist}-a{a:g}-{th:g}", ("roughconductor", dict(distribution=dist, alpha=a)),
                              wi_at(th), (a,)))
        for th in (30.0, 75.0):
            cases.append((f"rc-{dist}-aniso-{th:g}", ("roughconductor", dict(distribution=dist, alpha_u=0.05,
                                                                              alpha_v=0.4, material="Au")),
                          wi_at(th) @ np.array([[0.8, 0.6, 0], [-0.6, 0.8, 0], [0, 0, 1]]), (0.05, 0.4)))
        cases.append((f"rc-{dist}-allnormals-60", ("roughconductor", dict(distribution=dist, alpha=0.3,
                                                                           sample_visible=False)), wi_at(60.0), (0.3,)))
        for a in (0.1, 0.5):
            for th, side in ((0.0, 1), (45.0, 1), (80.0, 1), (20.0, -1), (45.0, -1), (80.0, -1)):
                cases.append((f"rd-{dist}-a{a:g}-{th:g}{'in' if side < 0 else 'out'}",
                              ("roughdielectric", dict(distribution=dist, alpha=a)), wi_at(th, side), (a,)))
        cases.append((f"rd-{dist}-aniso-40out", ("roughdielectric", dict(distribution=dist, alpha_u=0.05, alpha_v=0.3)),
                      wi_at(40.0) @ np.array([[0.6, 0.8, 0], [-0.8, 0.6, 0], [0, 0, 1]]), (0.05, 0.3)))
        cases.append((f"rd-{dist}-diamond-60in", ("roughdielectric", dict(distribution=dist, alpha=0.2,
                                                                            int_ior="diamond")), wi_at(60.0, -1), (0.2,)))
        cases.append((f"rd-{dist}-allnormals-30out", ("roughdielectric", dict(distribution=dist, alpha=0.3,
                                                                                sample_visible=False)),
                      wi_at(30.0), (0.3,)))
    return cases


CASES = _cases()
N_CHI2 = len(CASES)
# The default run samples a cross-section (each distribution: grazing, anisotropic, all normals, both sides of a
# dielectric, total internal reflection, a high index); the whole sweep is marked slow.
DEFAULT_CASES = {f"{p}-{d}-{c}" for d in ("beckmann", "ggx") for p, c in (
    ("rc", "a0.3-45"), ("rc", "a0.05-88"), ("rc", "aniso-75"), ("rc", "allnormals-60"),
    ("rd", "a0.1-0out"), ("rd", "a0.5-80out"), ("rd", "a0.1-45in"), ("rd", "a0.5-80in"), ("rd", "aniso-40out"),
    ("rd", "diamond-60in"))}
CASE_PARAMS = [pytest.param(c[0], marks=() if c[0] in DEFAULT_CASES else pytest.mark.slow) for c in CASES]


def _grid_for(bsdf, wi, alphas):
    """Integration points refined around the specular peaks (the mirror direction, and for dielectrics the
    refracted one) at two scales: the lobe's width and its width across the plane of incidence."""
    a = max(alphas)
    peaks = []
    if a < 0.6:
        targets = [wi * np.array([-1, -1, 1])]
        if hasattr(bsdf, "int_ior"):
            t = refracted(wi, bsdf.ext_ior, bsdf.int_ior)
            if t is not None:
                targets.append(t)
        for d in targets:
            peaks.append((d, min(14 * a, np.pi)))
            peaks.append((d, 14 * a * max(abs(wi[2]), 0.03)))
            # refraction out of air squeezes the lobe by about (1 - ext/int)
            peaks.append((d, 4 * a * 0.3))
    return refined_direction_grid(RES, SUB, peaks, n_fine=300)


def run_chi2(ctx, queue, bsdf, wi, alphas, n=N_SAMPLES, seed=7, pdf_row=None):
    s = bsdf_sample_batch(ctx, queue, bsdf.pack(), wi, n, seed)
    keep = np.any(s.weight != 0, axis=1)
    obs = bin_directions(s.wo[keep], RES)
    dirs, w, cell = _grid_for(bsdf, wi, alphas)
    pdf, _ = bsdf_pdf_eval_batch(ctx, queue, bsdf.pack() if pdf_row is None else pdf_row, wi, dirs)
    exp = expected_from_grid(pdf, w, cell, (RES, 2 * RES), n)
    return s, keep, obs, exp


class _Runs(dict):
    """Each case's samples and chi-square result, computed when a test first asks for it."""

    def __init__(self, ctx, queue):
        super().__init__()
        self.ctx, self.queue = ctx, queue

    def __missing__(self, name):
        _, (kind, kw), wi, alphas = next(c for c in CASES if c[0] == name)
        s, keep, obs, exp = run_chi2(self.ctx, self.queue, make(kind, **kw), wi, alphas)
        self[name] = (s, keep, chi2_test(obs, exp, min_exp=5.0, alpha=ALPHA, n_tests=N_CHI2), exp.sum(), wi)
        return self[name]


@pytest.fixture(scope="module")
def chi2_runs(ctx, queue):
    return _Runs(ctx, queue)


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_chi2_sample_vs_pdf(chi2_runs, name):
    s, keep, res, total, wi = chi2_runs[name]
    assert res.passed, f"{name}: {res.message}"


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_pdf_integral_is_the_surviving_fraction(chi2_runs, name):
    """∫ pdf = P(a sample survives) <= 1: = 1 up to what visible normals scatter below the horizon (or, for
    dielectrics, into the wrong side); a binomial bound of 5 sigma plus the quadrature's 0.3%."""
    s, keep, res, total, wi = chi2_runs[name]
    kept = check_pdf_integral(total, keep, name)
    if name.endswith(("-a0.05-0", "-a0.1-0out")):   # smooth enough that (almost) nothing is lost
        assert kept > 0.99, f"{name}: at normal incidence almost every sample must survive, kept {kept:.4f}"


@pytest.mark.parametrize("name", CASE_PARAMS)
def test_weight_is_eval_cos_over_pdf(chi2_runs, name):
    s, keep, res, total, wi = chi2_runs[name]
    refl = check_sample_weights(s, keep, wi)   # eta 1 for reflections; eta_t / eta_i for refractions, below
    if name.startswith("rd-") and (~refl).any():
        e = s.eta[keep][~refl]
        ratio = 2.419 / 1.000277 if "diamond" in name else 1.5046 / 1.000277
        np.testing.assert_allclose(e, ratio if wi[2] > 0 else 1 / ratio, rtol=1e-5)


# --------------------------------------------------------------------- the chi2 test must catch bugs
def test_chi2_rejects_wrong_pdfs(ctx, queue):
    # visible-normal samples scored against the density of all normals, and a 10% different alpha
    for kind, dist in (("roughconductor", "ggx"), ("roughconductor", "beckmann"), ("roughdielectric", "ggx")):
        bsdf = make(kind, distribution=dist, alpha=0.3)
        wrong = row(kind, distribution=dist, alpha=0.3, sample_visible=False)
        _, _, obs, exp = run_chi2(ctx, queue, bsdf, wi_at(70.0), (0.3,), pdf_row=wrong)
        assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed, (kind, dist)
        other = row(kind, distribution=dist, alpha=0.33)
        _, _, obs, exp = run_chi2(ctx, queue, bsdf, wi_at(30.0), (0.3,), pdf_row=other)
        assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed, (kind, dist)
    # anisotropy turned by 90 degrees
    bsdf = make("roughconductor", alpha_u=0.1, alpha_v=0.3)
    _, _, obs, exp = run_chi2(ctx, queue, bsdf, wi_at(50.0), (0.1, 0.3), pdf_row=row("roughconductor", alpha_u=0.3,
                                                                                          alpha_v=0.1))
    assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed


# ------------------------------------------------------------------------------------ energy / furnace
def mean_le(w, bound, a):
    """The mean of w is not significantly above bound (one-sided t-test at level a)."""
    w = np.asarray(w, np.float64)
    if w.mean() <= bound:
        return True
    return stats.ttest_1samp(w, bound, alternative="greater").pvalue > a


def test_white_furnace(ctx, queue):
    """A lossless rough mirror (material none: F = 1) returns at most what arrives (Smith's single scattering loses
    the rest); a dielectric's reflected plus transmitted importance (weight · eta² for refractions) as well, from
    either side; and a smooth dielectric and the thin sheet exactly what arrives."""
    cases = []
    for dist in ("beckmann", "ggx"):
        for a in (0.1, 0.5, 1.0):
            for th in (0.0, 60.0, 85.0):
                cases.append((make("roughconductor", distribution=dist, alpha=a), wi_at(th)))
                cases.append((make("roughdielectric", distribution=dist, alpha=a), wi_at(th)))
                cases.append((make("roughdielectric", distribution=dist, alpha=a), wi_at(th, -1)))
    a_t = sidak(ALPHA, len(cases))
    for bsdf, wi in cases:
        s = bsdf_sample_batch(ctx, queue, bsdf.pack(), wi, 100000, 41)
        w = s.weight[:, 0].astype(np.float64) * s.eta.astype(np.float64) ** 2
        assert mean_le(w, 1.0, a_t), f"{type(bsdf).__name__} {bsdf.distribution.name} " \
                                     f"{bsdf.distribution.alpha_u} {wi}: mean {w.mean():.5f}"
        # small roughness at normal incidence: almost nothing is lost
        if bsdf.distribution.alpha_u[0] == 0.1 and wi[2] > 0.99:
            assert w.mean() > 0.985
    for kind in ("dielectric", "thindielectric"):
        for wi in (wi_at(0.0), wi_at(70.0), wi_at(30.0, -1), wi_at(60.0, -1)):
            s = bsdf_sample_batch(ctx, queue, row(kind), wi, 20000, 43)
            np.testing.assert_allclose(s.weight[:, 0] * s.eta ** 2, 1.0, rtol=1e-5)


def test_reciprocity(ctx, queue):
    """f(wi, wo) = f(wo, wi) for reflection; for refraction f(wo, wi) = (eta_o / eta_i)^2 f(wi, wo) in the radiance
    form (eta_o: the index on wo's side)."""
    rng = np.random.default_rng(17)
    m = 4000
    wi = rng.normal(size=(m, 3))
    wo = rng.normal(size=(m, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    for kind, kw in (("roughconductor", dict(alpha_u=0.2, alpha_v=0.5, material="Cu")),
                     ("roughconductor", dict(distribution="ggx", alpha=0.3)),
                     ("roughdielectric", dict(alpha=0.4)),
                     ("roughdielectric", dict(distribution="ggx", alpha_u=0.3, alpha_v=0.6, int_ior=1.33))):
        bsdf = make(kind, **kw)
        r = bsdf.pack()
        _, f1 = bsdf_pdf_eval_batch(ctx, queue, np.array([r]), wi, wo, row_index=np.zeros(m))



        _, f2 = bsdf_pdf_eval_batch(ctx, queue, np.array([r]), wo, wi, row_index=np.zeros(m))
        scale = np.ones(m)
        if kind == "roughdielectric":
            ein, eex = bsdf.int_ior, bsdf.ext_ior
            trans = wi[:, 2] * wo[:, 2] < 0
            eta_o = np.where(wo[:, 2] > 0, eex, ein)
            eta_i = np.where(wi[:, 2] > 0, eex, ein)
            scale = np.where(trans, (eta_o / eta_i) ** 2, 1.0)
        assert (f1[:, 0] > 0).sum() > m // 10
        np.testing.assert_allclose(f2, f1 * scale[:, None], rtol=2e-3, atol=1e-6 * f1.max())


# ----------------------------------------------------------------------------------- against Mitsuba
@functools.lru_cache(maxsize=None)
def _values():
    return json.loads(VALUES.read_text())


def _ref_cases(kinds):
    return [c for c in _values()["cases"] if c["type"] in kinds]


def _id(c):
    return c["type"] + "-" + "-".join(f"{k}={v[1]}" for k, v in c["props"].items())


GLOSSY_REFS = _ref_cases(("roughconductor", "roughdielectric"))
DELTA_REFS = _ref_cases(("conductor", "dielectric", "thindielectric"))


def _instance(c):
    return make(c["type"], {k: (t, tuple(v) if t == "color" else v) for k, (t, v) in c["props"].items()})


@pytest.mark.parametrize("case", GLOSSY_REFS, ids=[_id(c) for c in GLOSSY_REFS])
def test_glossy_values_match_mitsuba(ctx, queue, case):
    r = _instance(case).pack()
    wi = np.asarray(_values()["wi"])
    wo = np.asarray(_values()["wo"])
    ref = np.asarray(case["f"])
    k = wo.shape[1]
    _, f = bsdf_pdf_eval_batch(ctx, queue, np.array([r]), np.repeat(wi, k, axis=0), wo.reshape(-1, 3),
                               row_index=np.zeros(len(wi) * k))
    ref = ref.reshape(-1, 3)
    assert (ref > 0).sum() > len(ref) // 4, "the reference set must exercise the lobe"
    np.testing.assert_allclose(f, ref, rtol=3e-3, atol=1e-5 * max(ref.max(), 1e-3))


@pytest.mark.parametrize("case", DELTA_REFS, ids=[_id(c) for c in DELTA_REFS])
def test_delta_events_match_mitsuba(ctx, queue, case):
    """For each wi: the reflection and transmission directions and weights Mitsuba samples, and how often each
    happens (Mitsuba's bs.pdf of the delta lobe; a binomial test)."""
    r = _instance(case).pack()
    n = 40000
    a = sidak(ALPHA, len(DELTA_REFS) * len(case["events"]))
    for wi, ev in zip(_values()["wi"], case["events"]):
        wi = np.asarray(wi)
        s = bsdf_sample_batch(ctx, queue, r, wi, n, 5)
        assert np.all(s.measure == 1)
        live = np.any(s.weight != 0, axis=1)
        refl = (s.wo[:, 2] * wi[2] > 0) & live
        trans = (s.wo[:, 2] * wi[2] < 0) & live
        for label, mask in (("reflect", refl), ("transmit", trans)):
            if label not in ev:
                assert not mask.any(), f"{case['type']} {wi}: {label} where Mitsuba has none"
                continue
            e = ev[label]
            assert mask.any(), f"{case['type']} {wi}: no {label} samples"
            np.testing.assert_allclose(s.wo[mask], np.broadcast_to(e["wo"], s.wo[mask].shape), atol=2e-6)
            np.testing.assert_allclose(s.weight[mask], np.broadcast_to(e["weight"], s.weight[mask].shape),
                                       rtol=2e-5, atol=1e-7)
            np.testing.assert_allclose(s.eta[mask], e["eta"], rtol=1e-5)
            if case["type"] != "conductor" and 0 < e["prob"] < 1:
                p = stats.binomtest(int(mask.sum()), n, e["prob"]).pvalue
                assert p > a, f"{case['type']} {wi} {label}: frequency {mask.mean():.5f} vs {e['prob']:.5f}"


def test_reference_file_is_mitsubas():
    v = _values()
    assert v["mitsuba_version"].startswith("3.") and v["variant"] == "scalar_rgb"
    assert {c["type"] for c in v["cases"]} == {"conductor", "roughconductor", "dielectric", "thindielectric",
                                               "roughdielectric"}


# ------------------------------------------------------------------------------------------ delta details
def test_conductor_presets_and_defaults(ctx, queue):
    """material none (the default) is a perfect mirror; presets give Mitsuba's RGB Fresnel at normal incidence."""
    s = bsdf_sample_batch(ctx, queue, row("conductor"), wi_at(40.0), 1000, 1)
    np.testing.assert_allclose(s.weight, 1.0, rtol=1e-6)
    s = bsdf_sample_batch(ctx, queue, row("conductor", material="Au"), wi_at(0.0), 10, 1)
    eta, k = (np.array(x) for x in MATERIALS["Au"])
    F0 = ((eta - 1) ** 2 + k ** 2) / ((eta + 1) ** 2 + k ** 2)
    np.testing.assert_allclose(s.weight[0], F0, rtol=1e-5)
    s = bsdf_sample_batch(ctx, queue, row("conductor", material="Au"), wi_at(30.0, -1), 10, 1)
    assert np.all(s.weight == 0), "one-sided: nothing from below"
    assert {"Au", "Ag", "Al", "Cu", "a-C", "W", "Cr"} <= set(MATERIALS)


def test_rough_bsdfs_are_not_delta_and_flags(ctx, queue):
    f = flag_defines()
    assert row("roughconductor")["flags"] & f["BSDF_GLOSSY"] and not row("roughconductor")["flags"] & f["BSDF_DELTA"]
    for kind in ("conductor", "dielectric", "thindielectric"):
        assert row(kind)["flags"] & f["BSDF_DELTA"]
    wo = np.array([[0, 0, 1], [0, 0, -1], [0.6, 0, 0.8]])
    for kind in ("conductor", "dielectric", "thindielectric"):
        pdf, fv = bsdf_pdf_eval_batch(ctx, queue, row(kind), (0, 0, 1), wo)
        assert np.all(pdf == 0) and np.all(fv == 0)


# ---------------------------------------------------------------------------------------------- textures
def _with_textures(kind, names, **kw):
    """A Mitsuba-format BSDF with Nori checkerboard textures nested under `names` (any texture plugin does)."""
    kids = []
    for name in names:
        tp = PropertyList('<texture type="checkerboard_color">')
        tp.add("value1", "color", (0.2, 0.4, 0.6))
        tp.add("value2", "color", (0.7, 0.5, 0.3))
        kids.append(PluginSpec("texture", "checkerboard_color", name, tp, [], None, format="nori"))
    pl = PropertyList(f'<bsdf type="{kind}">', fmt="mitsuba")
    for k, (t, v) in _props(**kw).items():
        pl.add(k, t, v)
    return create(PluginSpec("bsdf", kind, None, pl, kids, None, format="mitsuba"))


def test_textured_parameters(ctx, queue):
    """A textured alpha reads the texture's first channel, a textured colour the texture: where the checkerboard
    shows value1 the BSDF equals the constant one with alpha 0.2 and colour value1, elsewhere 0.7 / value2."""
    rng = np.random.default_rng(4)
    wi = np.array([0.3, 0.2, 0.93])
    wo = rng.normal(size=(500, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    uv1, uv2 = (0.1, 0.1), (0.6, 0.1)   # cells (0,0) and (1,0) of the default 0.5 grid
    for kind, names, colour, extra in (
            ("roughconductor", ("alpha", "specular_reflectance"), "specular_reflectance", {}),
            ("roughdielectric", ("alpha", "specular_transmittance"), "specular_transmittance", {})):
        b = _with_textures(kind, names, **extra)
        r = b.pack()
        assert r["flags"] & flag_defines()["BSDF_UV"]
        tex = b.textures_table
        for uv, a, c in ((uv1, 0.2, (0.2, 0.4, 0.6)), (uv2, 0.7, (0.7, 0.5, 0.3))):
            ref = row(kind, alpha=a, **{colour: c})
            wo_use = wo if kind == "roughconductor" else wo * np.array([1, 1, -1])
            p1, f1 = bsdf_pdf_eval_batch(ctx, queue, r, wi, wo_use, uv=uv, textures=tex)
            p2, f2 = bsdf_pdf_eval_batch(ctx, queue, ref, wi, wo_use, uv=uv)
            assert f2.max() > 0
            np.testing.assert_allclose(f1, f2, rtol=1e-5, atol=1e-7)
            np.testing.assert_allclose(p1, p2, rtol=1e-5, atol=1e-7)
    # one textured alpha of an anisotropic pair
    b = _with_textures("roughconductor", ("alpha_u",), alpha_v=0.3, distribution="ggx")
    for uv, a in ((uv1, 0.2), (uv2, 0.7)):
        _, f1 = bsdf_pdf_eval_batch(ctx, queue, b.pack(), wi, wo, uv=uv, textures=b.textures_table)
        _, f2 = bsdf_pdf_eval_batch(ctx, queue, row("roughconductor", alpha_u=a, alpha_v=0.3, distribution="ggx"),
                                    wi, wo, uv=uv)
        np.testing.assert_allclose(f1, f2, rtol=1e-5, atol=1e-7)
    b = _with_textures("conductor", ("specular_reflectance",))
    s = bsdf_sample_batch(ctx, queue, b.pack(), wi_at(20.0), 2, 1, uv=uv2, textures=b.textures_table)
    np.testing.assert_allclose(s.weight, [[0.7, 0.5, 0.3]] * 2, rtol=1e-6)


# ------------------------------------------------------------------------------------------------ errors
def test_named_iors():
    assert lookup_ior("BK7") == 1.5046 and lookup_ior("diamond") == 2.419 and lookup_ior("Water Ice") == 1.31
    assert len(NAMED_IORS) == 23
    b = make("dielectric", int_ior="diamond", ext_ior="water")
    assert (b.int_ior, b.ext_ior) == (2.419, 1.333)
    b = make("roughdielectric")
    assert (b.int_ior, b.ext_ior) == (1.5046, 1.000277)
    with pytest.raises(SceneError, match="unknown index of refraction name 'glas'.*bk7"):
        make("dielectric", int_ior="glas")


@pytest.mark.parametrize("kind,kw,message", [
    ("conductor", dict(material="Gold"), "unknown conductor material 'Gold'; known: none, a-C"),
    ("conductor", dict(material="Au", eta=(1.0, 1.0, 1.0)), "either material or eta and k"),
    ("roughconductor", dict(distribution="phong"), "distribution must be one of beckmann, ggx"),
    ("roughconductor", dict(alpha_u=0.1), "both alpha_u and alpha_v"),
    ("roughdielectric", dict(alpha=0.1, alpha_u=0.1, alpha_v=0.2), "either alpha or alpha_u"),
    ("roughdielectric", dict(alpha=-0.1), "alpha must be positive"),
    ("thindielectric", dict(int_ior=-1.0), "int_ior must be positive"),
    ("dielectric", dict(specular_reflectance=(-1.0, 0.0, 0.0)), "specular_reflectance must be non-negative"),
    ("roughconductor", dict(roughness=0.1), "property 'roughness' is not used"),
])
def test_scene_errors(kind, kw, message):
    with pytest.raises(SceneError, match=message):
        make(kind, **kw)
