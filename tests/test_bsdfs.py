"""kernels/bsdf.h on the device: chi-square of sample() against pdf(), sample weights against eval()·cos/pdf(),
the delta BSDFs' directions, frequencies and weights, energy (white furnace), textures, and a check that the
chi-square machinery rejects a wrong pdf.

All chi-square cases of this module share one Šidák correction (N_CHI2 tests at overall level ALPHA).
"""
import numpy as np
import pytest
from scipy import stats

from clrender import plugins  # noqa: F401  (registers the plugins)
from clrender.device.dispatch import flag_defines, tag_of
from clrender.errors import SceneError
from clrender.scene.registry import create
from clrender.scene.xmlparser import parse_string
from clrender.testing.chi2 import (bin_directions, chi2_test, expected_from_grid, refined_direction_grid,
                                   sidak)
from clrender.testing.kernels import bsdf_pdf_eval_batch, bsdf_sample_batch

ALPHA = 0.01
RES = 10                      # Nori's chi2test: 10 cos(theta) bins x 20 phi bins
N_SAMPLES = 5000 * RES * RES  # Nori/Mitsuba use 5000 res^2 samples (Nori's default doubles it)
SUB = 8                       # midpoint sub-cells per cell and axis (plus refinement around peaks)
ANGLES = (0.0, 30.0, 60.0, 85.0)
INT_IOR, EXT_IOR = 1.5046, 1.000277


# ------------------------------------------------------------------------------------------- rows
# Rows are always built by the plugins themselves (from XML), never by hand.
def plugin_row(xml):
    import clrender.plugins  # noqa: F401

    spec = parse_string(f"<scene>{xml}</scene>", "row.xml")
    return create(next(s for s in spec.walk() if s.tag == "bsdf")).pack()


def _c(v):
    return ", ".join(repr(float(x)) for x in np.broadcast_to(np.asarray(v, np.float64), (3,)))


def row_diffuse(albedo):
    return plugin_row(f'<bsdf type="diffuse"><color name="albedo" value="{_c(albedo)}"/></bsdf>')


def row_microfacet(alpha, kd, int_ior=INT_IOR, ext_ior=EXT_IOR):
    return plugin_row(f'<bsdf type="microfacet"><float name="alpha" value="{alpha!r}"/><color name="kd" '
                      f'value="{_c(kd)}"/><float name="intIOR" value="{int_ior!r}"/>'
                      f'<float name="extIOR" value="{ext_ior!r}"/></bsdf>')


def row_mirror():
    return plugin_row('<bsdf type="mirror"/>')


def row_dielectric(int_ior=INT_IOR, ext_ior=EXT_IOR):
    return plugin_row(f'<bsdf type="dielectric"><float name="intIOR" value="{int_ior!r}"/>'
                      f'<float name="extIOR" value="{ext_ior!r}"/></bsdf>')


def wi_at(theta_deg):
    t = np.radians(theta_deg)
    return np.array([np.sin(t), 0.0, np.cos(t)])


# ------------------------------------------------------------------------------- host references (f64)
def fresnel(cos_i, eta_ext, eta_int):
    with np.errstate(all="ignore"):
        return _fresnel(cos_i, eta_ext, eta_int)


def _fresnel(cos_i, eta_ext, eta_int):
    cos_i = np.asarray(cos_i, np.float64)
    inside = cos_i < 0
    ei = np.where(inside, eta_int, eta_ext)
    et = np.where(inside, eta_ext, eta_int)
    c = np.abs(cos_i)
    sin2_t = (ei / et) ** 2 * np.maximum(0, 1 - c * c)
    tir = sin2_t >= 1
    ct = np.sqrt(np.maximum(0, 1 - sin2_t))
    rs = (ei * c - et * ct) / (ei * c + et * ct)
    rp = (et * c - ei * ct) / (et * c + ei * ct)
    return np.where(tir, 1.0, 0.5 * (rs * rs + rp * rp))


def microfacet_f_ref(wi, wo, alpha, kd, int_ior=INT_IOR, ext_ior=EXT_IOR):
    """Nori's microfacet BRDF from the formulas (float64), (m,3)."""
    with np.errstate(all="ignore"):
        return _microfacet_f_ref(wi, wo, alpha, kd, int_ior, ext_ior)


def _microfacet_f_ref(wi, wo, alpha, kd, int_ior, ext_ior):
    wi = np.broadcast_to(np.asarray(wi, np.float64), np.shape(wo))
    wo = np.asarray(wo, np.float64)
    kd = np.broadcast_to(np.asarray(kd, np.float64), (3,))
    ks = 1 - kd.max()
    h = wi + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    ch = np.clip(h[:, 2], 1e-300, None)
    tan2 = (1 - ch * ch) / (ch * ch)
    D = np.where(h[:, 2] > 0, np.exp(-tan2 / alpha**2) / (np.pi * alpha**2 * ch**4), 0.0)
    F = fresnel(np.sum(h * wi, 1), ext_ior, int_ior)

    def g1(v):
        cz = v[:, 2]
        tan_t = np.sqrt(np.maximum(0, 1 - cz * cz)) / cz
        b = 1 / (alpha * tan_t)
        g = np.where(b < 1.6, (3.535 * b + 2.181 * b * b) / (1 + 2.276 * b + 2.577 * b * b), 1.0)
        return np.where(np.sum(v * h, 1) / cz <= 0, 0.0, g)

    spec = D * F * g1(wi) * g1(wo) / (4 * wi[:, 2] * wo[:, 2])
    f = kd[None, :] / np.pi + ks * spec[:, None]
    ok = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    return np.where(ok[:, None], f, 0.0)


# --------------------------------------------------------------------------------------- chi2 cases
def _cases():
    cases = []
    for th in ANGLES:
        cases.append((f"diffuse-grey-{th:g}", row_diffuse(0.5), th, None))
    cases.append(("diffuse-colour-30", row_diffuse((0.2, 0.5, 0.9)), 30.0, None))
    for alpha in (0.01, 0.1, 0.5, 1.0):
        for kdname, kd in (("kd0", 0.0), ("kd05", 0.5), ("kdrgb", (0.1, 0.3, 0.6))):
            for th in ANGLES:
                cases.append((f"microfacet-a{alpha:g}-{kdname}-{th:g}", row_microfacet(alpha, kd), th, alpha))
    return cases


CASES = _cases()
N_CHI2 = len(CASES)


def _grid_for(theta, alpha):
    # Around the mirror direction of wi, where the specular lobe is: the half-vector spreads by a few alpha
    # (tan^2 = -alpha^2 log(1-u): 1e-9 of the mass lies beyond 4.6 alpha), wo by twice that in the plane of
    # incidence but only by 2 alpha cos(theta_i) across it (narrow at grazing angles): refine at both scales.
    peaks = []
    if alpha is not None and alpha < 0.6:
        wr = wi_at(theta) * np.array([-1, -1, 1])
        peaks.append((wr, min(12 * alpha, np.pi)))
        peaks.append((wr, 12 * alpha * max(np.cos(np.radians(theta)), 0.02)))
    return refined_direction_grid(RES, SUB, peaks, n_fine=400)


def run_chi2_case(ctx, queue, row, theta, alpha, n=N_SAMPLES, seed=7, pdf_fn=None):
    """Sample, bin (zero-weight samples dropped, as in Nori), integrate pdf() (or pdf_fn) over the cells."""
    wi = wi_at(theta)
    s = bsdf_sample_batch(ctx, queue, row, wi, n, seed)
    keep = np.any(s.weight != 0, axis=1)
    obs = bin_directions(s.wo[keep], RES)
    dirs, w, cell = _grid_for(theta, alpha)
    if pdf_fn is None:
        pdf, _ = bsdf_pdf_eval_batch(ctx, queue, row, wi, dirs)
    else:
        pdf = pdf_fn(dirs)
    exp = expected_from_grid(pdf, w, cell, (RES, 2 * RES), n)
    return s, keep, obs, exp


@pytest.fixture(scope="module")
def chi2_runs(ctx, queue):
    out = {}
    for name, row, th, alpha in CASES:
        s, keep, obs, exp = run_chi2_case(ctx, queue, row, th, alpha)
        res = chi2_test(obs, exp, min_exp=5.0, alpha=ALPHA, n_tests=N_CHI2)
        out[name] = (s, keep, res, row, th)
    return out


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_chi2_sample_vs_pdf(chi2_runs, name):
    s, keep, res, row, th = chi2_runs[name]
    assert res.passed, f"{name}: {res.message}"


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_weight_is_eval_cos_over_pdf(chi2_runs, name):
    s, keep, res, row, th = chi2_runs[name]
    assert np.all(s.measure == 0)
    assert np.all(np.isfinite(s.weight))
    w, f, pdf, cos = s.weight[keep], s.f[keep], s.pdf[keep], s.wo[keep, 2]
    assert np.all(pdf > 0), "a sample with weight has zero pdf"
    assert np.all(cos > 0)
    ref = f * (cos / pdf)[:, None]
    np.testing.assert_allclose(w, ref, rtol=2e-4, atol=1e-7)
    # and the other way round: a dropped (zero-weight) sample points below the surface or has f = 0
    drop = ~keep
    assert np.all((s.wo[drop, 2] <= 0) | np.all(s.f[drop] == 0, axis=1))


def test_microfacet_eval_matches_formula(ctx, queue):
    rng = np.random.default_rng(3)
    m = 20000
    for alpha in (0.05, 0.2, 0.7):
        for kd in (0.0, (0.1, 0.3, 0.6)):
            row = row_microfacet(alpha, kd)
            wi = rng.normal(size=(m, 3))
            wi[:, 2] = np.abs(wi[:, 2]) + 0.05
            wi /= np.linalg.norm(wi, axis=1, keepdims=True)
            # wo near the mirror direction (where the lobe is), and some anywhere (also below)
            wr = wi * np.array([-1, -1, 1])
            wo = wr + rng.normal(scale=alpha, size=(m, 3))
            wo[m // 2:] = rng.normal(size=(m - m // 2, 3))
            wo /= np.linalg.norm(wo, axis=1, keepdims=True)
            pdf, f = bsdf_pdf_eval_batch(ctx, queue, row, wi, wo)
            ref = microfacet_f_ref(wi, wo, alpha, kd)
            np.testing.assert_allclose(f, ref, rtol=2e-3, atol=1e-6 * ref.max())
            # pdf from the formula, too
            h = wi + wo
            h /= np.linalg.norm(h, axis=1, keepdims=True)
            ch = np.clip(h[:, 2], 1e-12, None)
            D = np.where(h[:, 2] > 0, np.exp(-((1 - ch**2) / ch**2) / alpha**2) / (np.pi * alpha**2 * ch**4), 0)
            ks = 1 - np.max(kd)
            p_ref = ks * D * ch / (4 * np.abs(np.sum(h * wo, 1))) + (1 - ks) * wo[:, 2] / np.pi
            p_ref = np.where((wi[:, 2] > 0) & (wo[:, 2] > 0), p_ref, 0)
            np.testing.assert_allclose(pdf, p_ref, rtol=2e-3, atol=1e-6 * p_ref.max())


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


# --------------------------------------------------------------------- the chi2 test must catch bugs
def test_chi2_rejects_wrong_pdfs(ctx, queue):
    # cosine-weighted samples scored against the uniform hemisphere density
    _, _, obs, exp = run_chi2_case(ctx, queue, row_diffuse(0.5), 30.0, None,
                                   pdf_fn=lambda d: np.where(d[:, 2] > 0, 1 / (2 * np.pi), 0.0))
    assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed
    # microfacet samples scored against a pdf that forgets the 1/(4|h.wo|) Jacobian of the reflection
    for kd in (0.0, 0.5):
        row = row_microfacet(0.3, kd)
        wi = wi_at(30.0)
        ks = 1 - kd

        def pdf_no_jacobian(d):
            h = d + wi
            h /= np.linalg.norm(h, axis=1, keepdims=True)
            ch = np.clip(h[:, 2], 1e-12, None)
            D = np.where(h[:, 2] > 0, np.exp(-((1 - ch**2) / ch**2) / 0.09) / (np.pi * 0.09 * ch**4), 0)
            return np.where(d[:, 2] > 0, ks * D * ch + (1 - ks) * d[:, 2] / np.pi, 0.0)

        _, _, obs, exp = run_chi2_case(ctx, queue, row, 30.0, 0.3, pdf_fn=pdf_no_jacobian)
        assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed
    # and a subtle one: alpha off by 10% in the pdf
    row = row_microfacet(0.1, 0.0)
    other = row_microfacet(0.11, 0.0)
    _, _, obs, _ = run_chi2_case(ctx, queue, row, 30.0, 0.1)
    dirs, w, cell = _grid_for(30.0, 0.1)
    pdf, _ = bsdf_pdf_eval_batch(ctx, queue, other, wi_at(30.0), dirs)
    exp = expected_from_grid(pdf, w, cell, (RES, 2 * RES), N_SAMPLES)
    assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed


# ------------------------------------------------------------------------------------ energy / furnace
def test_diffuse_white_furnace(ctx, queue):
    for th in ANGLES:
        s = bsdf_sample_batch(ctx, queue, row_diffuse(1.0), wi_at(th), 200000, 11)
        assert np.all(s.weight == 1.0)


def _albedo_quadrature(theta, alpha, kd):
    wi = wi_at(theta)
    wr = wi * np.array([-1, -1, 1])
    peaks = [(wr, min(12 * alpha, np.pi)), (wr, 12 * alpha * max(wi[2], 0.02))] if alpha < 0.6 else []
    dirs, w, _ = refined_direction_grid(16, 8, peaks, n_fine=600)
    f = microfacet_f_ref(wi, dirs, alpha, kd)
    return (f * np.maximum(dirs[:, 2], 0)[:, None] * w[:, None]).sum(0)


def mean_agrees(w, ref, a, rel=1e-3):
    """Student's t-test of the mean of w against ref at level a, except that a relative difference below
    `rel` (float32 arithmetic, quadrature) always passes: near-constant weights make the t-test too sharp."""
    w = np.asarray(w, np.float64)
    if abs(w.mean() - ref) <= rel * abs(ref):
        return True, 1.0
    p = stats.ttest_1samp(w, ref).pvalue
    return p > a, p


def test_microfacet_energy(ctx, queue):
    """Mean sample weight = directional albedo ∫ f cos dwo. For kd = 0, changing variables to h
    (dwo = 4 |wi.h| dh) gives albedo = ∫ D(h) F(wi.h) G1(wi) G1(wo) (wi.h)/cos_i dh; Smith's
    normalisation ∫ D (wi.h)+ dh = cos_i / G1(wi) makes this E_vis[F G1(wo)] <= max F <= 1 (up to the
    rational fit's error), and for small alpha away from grazing it is F(cos_i) (h ~ n, G1 ~ 1)."""
    cases = [(a, th) for a in (0.1, 0.5, 1.0) for th in (0.0, 30.0, 60.0, 85.0)]
    a_t = sidak(ALPHA, len(cases) + 4)
    for alpha, th in cases:
        s = bsdf_sample_batch(ctx, queue, row_microfacet(alpha, 0.0), wi_at(th), 400000, 21)
        w = s.weight[:, 0].astype(np.float64)
        mean = w.mean()
        assert mean <= 1.0
        ref = _albedo_quadrature(th, alpha, 0.0)[0]
        ok, p = mean_agrees(w, ref, a_t)
        assert ok, f"alpha {alpha} theta {th}: mean {mean:.6f} vs quadrature {ref:.6f} (p={p:.3g})"
        assert ref <= fresnel(np.cos(np.radians(min(th + 3 * alpha * 57.3, 89.9))), EXT_IOR, INT_IOR) * 1.02
        if alpha <= 0.1 and th <= 60:
            F = fresnel(np.cos(np.radians(th)), EXT_IOR, INT_IOR)
            assert abs(mean - F) < 0.03 * F + 5 * w.std() / np.sqrt(len(w))
    # with a diffuse part (coloured kd): albedo per channel
    for alpha, th in ((0.1, 30.0), (0.5, 60.0)):
        kd = (0.1, 0.3, 0.6)
        s = bsdf_sample_batch(ctx, queue, row_microfacet(alpha, kd), wi_at(th), 400000, 23)
        ref = _albedo_quadrature(th, alpha, kd)
        for c in (0, 2):
            ok, p = mean_agrees(s.weight[:, c], ref[c], a_t)
            assert ok, f"kd {kd} alpha {alpha} theta {th} channel {c}: p={p:.3g}"


# ------------------------------------------------------------------------------------------ mirror
def test_mirror(ctx, queue):
    rng = np.random.default_rng(5)
    wi = rng.normal(size=(5000, 3))
    wi[:, 2] = np.abs(wi[:, 2]) + 1e-3
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wi32 = wi.astype(np.float32)
    s = bsdf_sample_batch(ctx, queue, row_mirror(), wi32, len(wi), 1)
    np.testing.assert_allclose(s.wo, wi32 * np.array([-1, -1, 1], np.float32), rtol=0, atol=1e-7)
    assert np.all(s.weight == 1) and np.all(s.measure == 1) and np.all(s.eta == 1)
    pdf, f = bsdf_pdf_eval_batch(ctx, queue, row_mirror(), wi, s.wo)
    assert np.all(pdf == 0) and np.all(f == 0)
    s = bsdf_sample_batch(ctx, queue, row_mirror(), (0.3, 0, -0.9), 100, 1)
    assert np.all(s.weight == 0)


# -------------------------------------------------------------------------------------- dielectric
DIEL_CASES = [(th, +1) for th in (0.0, 30.0, 60.0, 85.0)] + [(th, -1) for th in (0.0, 20.0, 40.0, 41.0, 45.0,
                                                                                   70.0)]


@pytest.fixture(scope="module")
def dielectric_runs(ctx, queue):
    out = {}
    for th, side in DIEL_CASES:
        wi = wi_at(th) * np.array([1, 1, side])
        out[(th, side)] = (wi, bsdf_sample_batch(ctx, queue, row_dielectric(), wi, 200000, 31))
    return out


def test_dielectric_frequencies_and_weights(dielectric_runs):
    a = sidak(ALPHA, 2 * len(DIEL_CASES))
    for (th, side), (wi, s) in dielectric_runs.items():
        wi32 = (wi / np.linalg.norm(wi)).astype(np.float32)
        F = float(fresnel(wi[2], EXT_IOR, INT_IOR))
        assert np.all(s.measure == 1)
        refl = s.wo[:, 2] * wi[2] > 0
        eta_i, eta_t = (EXT_IOR, INT_IOR) if side > 0 else (INT_IOR, EXT_IOR)
        k = int(refl.sum())
        n = len(refl)
        if F >= 1:
            assert k == n, "total internal reflection must always reflect"
        else:
            p = stats.binomtest(k, n, F).pvalue
            assert p > a, f"theta {th} side {side}: reflected {k / n:.5f}, Fresnel {F:.5f} (p={p:.3g})"
        # reflection: exact mirror, weight 1, eta 1
        np.testing.assert_allclose(s.wo[refl], np.broadcast_to(wi32 * np.array([-1, -1, 1]), s.wo[refl].shape),
                                   atol=1e-7)
        assert np.all(s.weight[refl] == 1) and np.all(s.eta[refl] == 1)
        # refraction: Snell, opposite azimuth, other side, unit length, weight (eta_i/eta_t)^2
        t = ~refl
        if t.any():
            wo = s.wo[t].astype(np.float64)
            np.testing.assert_allclose(np.linalg.norm(wo, axis=1), 1, atol=1e-6)
            sin_i = np.hypot(wi[0], wi[1])
            np.testing.assert_allclose(eta_t * np.hypot(wo[:, 0], wo[:, 1]), eta_i * sin_i, atol=2e-6)
            if sin_i > 0:
                assert np.all(wo[:, 0] * wi[0] <= 0)
            assert np.all(np.sign(wo[:, 2]) == -side)
            np.testing.assert_allclose(s.weight[t], (eta_i / eta_t) ** 2, rtol=1e-6)
            np.testing.assert_allclose(s.eta[t], eta_t / eta_i, rtol=1e-6)


def test_dielectric_expected_weight(dielectric_runs):
    """One sample's expected weight at normal incidence: F + (1-F)(eta_i/eta_t)^2, from outside and inside."""
    a = sidak(ALPHA, 2)
    for side in (+1, -1):
        wi, s = dielectric_runs[(0.0, side)]
        F = float(fresnel(side * 1.0, EXT_IOR, INT_IOR))
        ratio = EXT_IOR / INT_IOR if side > 0 else INT_IOR / EXT_IOR
        expect = F + (1 - F) * ratio**2
        w = s.weight[:, 0].astype(np.float64)
        ok, p = mean_agrees(w, expect, a, rel=0)
        assert ok, f"side {side}: mean {w.mean():.5f} vs {expect:.5f}"


def test_delta_eval_pdf_zero(ctx, queue):
    wo = np.array([[0, 0, 1], [0, 0, -1], [0.6, 0, 0.8]])
    for row in (row_mirror(), row_dielectric()):
        pdf, f = bsdf_pdf_eval_batch(ctx, queue, row, (0, 0, 1), wo)
        assert np.all(pdf == 0) and np.all(f == 0)


# ---------------------------------------------------------------------------------------- textures
CHECKER_XML = """<scene><mesh type="obj"><string name="filename" value="x.obj"/>
  <bsdf type="{kind}">
    <texture type="checkerboard_color" name="{name}">
      <color name="value1" value="0.8, 0.1, 0.1"/>
      <color name="value2" value="0.1, 0.2, 0.7"/>
      <point name="delta" value="0.05, -0.1"/>
      <vector name="scale" value="0.25 0.5"/>
    </texture>{extra}
  </bsdf></mesh></scene>"""


def _bsdf_from(xml):
    spec = parse_string(xml, "t.xml")
    b = next(s for s in spec.walk() if s.tag == "bsdf")
    return create(b)


def test_checkerboard_texture(ctx, queue):
    bsdf = _bsdf_from(CHECKER_XML.format(kind="diffuse", name="albedo", extra=""))
    row = bsdf.pack()
    assert row["flags"] & flag_defines()["BSDF_UV"] and row["diffuse"]["albedo_tex"] == 0
    tex = bsdf.textures_table
    assert len(tex) == 1 and tex[0]["type"] == tag_of(type(bsdf.texture))
    rng = np.random.default_rng(9)
    uv = rng.uniform(-2, 2, (4000, 2))
    # stay away from the cell edges, where float32 and float64 may disagree
    fr = np.stack([(uv[:, 0] - 0.05) / 0.25, (uv[:, 1] + 0.1) / 0.5], 1)
    uv = uv[np.all(np.abs(fr - np.round(fr)) > 1e-4, axis=1)]
    ref = bsdf.texture.eval(uv)
    assert 0.3 < np.mean(ref[:, 0] == 0.8) < 0.7
    pdf, f, alb = bsdf_pdf_eval_batch(ctx, queue, row, (0, 0, 1), np.tile([0.0, 0.0, 1.0], (len(uv), 1)), uv=uv,
                                      with_albedo=True, textures=tex)
    np.testing.assert_allclose(alb, ref, rtol=1e-6)
    np.testing.assert_allclose(f, ref / np.pi, rtol=1e-6)
    s = bsdf_sample_batch(ctx, queue, row, (0, 0, 1), len(uv), 3, uv=uv, textures=tex)
    np.testing.assert_allclose(s.weight, ref, rtol=1e-6)
    # a few hand-checked points: cell (0,0) is value1, its neighbours value2
    pts = np.array([[0.1, 0.0], [0.35, 0.0], [0.1, 0.45], [0.35, 0.45], [-0.1, 0.0]])
    _, _, alb = bsdf_pdf_eval_batch(ctx, queue, row, (0, 0, 1), np.tile([0.0, 0.0, 1.0], (5, 1)), uv=pts,
                                    with_albedo=True, textures=tex)
    v1, v2 = [0.8, 0.1, 0.1], [0.1, 0.2, 0.7]
    np.testing.assert_allclose(alb, [v1, v2, v2, v1, v2], rtol=1e-6)


def test_checkerboard_on_microfacet(ctx, queue):
    bsdf = _bsdf_from(CHECKER_XML.format(kind="microfacet", name="kd", extra=""))
    row = bsdf.pack()
    tex = bsdf.textures_table
    assert abs(row["microfacet"]["ks"] - (1 - 0.8)) < 1e-6
    _, _, alb = bsdf_pdf_eval_batch(ctx, queue, row, (0, 0, 1), [[0, 0, 1], [0, 0, 1]],
                                    uv=np.array([[0.1, 0.0], [0.35, 0.0]]), with_albedo=True, textures=tex)
    np.testing.assert_allclose(alb, [[0.8, 0.1, 0.1], [0.1, 0.2, 0.7]], rtol=1e-6)


def test_checkerboard_errors():
    with pytest.raises(SceneError):
        _bsdf_from(CHECKER_XML.format(kind="diffuse", name="kd", extra=""))
    with pytest.raises(SceneError):
        _bsdf_from(CHECKER_XML.format(kind="diffuse", name="albedo",
                                      extra='<color name="albedo" value="0.5"/>'))
    with pytest.raises(SceneError):
        _bsdf_from(CHECKER_XML.format(kind="mirror", name="albedo", extra=""))


def test_bsdf_is_delta_and_albedo(ctx, queue):
    rows = np.array([row_diffuse((0.2, 0.3, 0.4)), row_mirror(), row_dielectric(), row_microfacet(0.2, 0.25)])
    pdf, f, alb = bsdf_pdf_eval_batch(ctx, queue, rows, (0, 0, 1), np.tile([0, 0, 1.0], (4, 1)),
                                      row_index=np.arange(4), with_albedo=True)
    np.testing.assert_allclose(alb, [[0.2, 0.3, 0.4], [1, 1, 1], [1, 1, 1], [0.25, 0.25, 0.25]], rtol=1e-6)
