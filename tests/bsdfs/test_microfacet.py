"""Nori's microfacet BSDF (a Beckmann specular lobe over a diffuse base: clrender/bsdfs/microfacet.py,
kernels/bsdfs/microfacet.h) on the device: chi-square of sample() against pdf(), sample weights against
eval()·cos/pdf(), eval and pdf against the formulas, energy (directional albedo against a quadrature of the formula),
a textured kd, and checks that the chi-square machinery rejects wrong pdfs.

All chi-square cases of this module share one Šidák correction (N_CHI2 tests at overall level ALPHA).
"""
import numpy as np
import pytest

from clrender.testing.plugin_checks import (ALPHA, FAMILIES, albedo_quadrature, bsdf_chi2, bsdf_from_xml,
                                            bsdf_pdf_eval_batch, bsdf_sample_batch, check_render_value, check_weights,
                                            chi2_test, fresnel, furnace_wi, lobe_grid, mean_agrees, plugin_row,
                                            refined_direction_grid, render_furnace_plane, sidak, wi_at)

from .test_diffuse import _c, row_diffuse

#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("microfacet", "dielectric", "diffuse", "mirror"), textures=("checkerboard_color",))


ANGLES = (0.0, 30.0, 60.0, 85.0)
INT_IOR, EXT_IOR = 1.5046, 1.000277


def row_microfacet(alpha, kd, int_ior=INT_IOR, ext_ior=EXT_IOR):
    return plugin_row(f'<bsdf type="microfacet"><float name="alpha" value="{alpha!r}"/><color name="kd" '
                      f'value="{_c(kd)}"/><float name="intIOR" value="{int_ior!r}"/>'
                      f'<float name="extIOR" value="{ext_ior!r}"/></bsdf>')


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
CASES = {f"microfacet-a{alpha:g}-{kdname}-{th:g}": (alpha, kd, th)
         for alpha in (0.01, 0.1, 0.5, 1.0)
         for kdname, kd in (("kd0", 0.0), ("kd05", 0.5), ("kdrgb", (0.1, 0.3, 0.6)))
         for th in ANGLES}
N_CHI2 = FAMILIES["nori-bsdf-chi2"]


def chi2_case(name):
    alpha, kd, th = CASES[name]
    return row_microfacet(alpha, kd), wi_at(th), lobe_grid(wi_at(th), alpha)


@pytest.mark.plugin("microfacet", "sampling")
@pytest.mark.parametrize("name", list(CASES))
def test_chi2_sample_vs_pdf(chi2_runs, name):
    chi2_runs.check(name)


@pytest.mark.parametrize("name", list(CASES))
def test_weight_is_eval_cos_over_pdf(chi2_runs, name):
    run = chi2_runs[name]
    check_weights(run.samples, run.keep)


@pytest.mark.plugin("microfacet", "eval")
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


# --------------------------------------------------------------------- the chi2 test must catch bugs
def test_chi2_rejects_wrong_pdfs(ctx, queue):
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

        _, _, obs, exp = bsdf_chi2(ctx, queue, row, wi, lobe_grid(wi, 0.3), pdf_fn=pdf_no_jacobian)
        assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed
    # and a subtle one: alpha off by 10% in the pdf
    wi = wi_at(30.0)
    _, _, obs, exp = bsdf_chi2(ctx, queue, row_microfacet(0.1, 0.0), wi, lobe_grid(wi, 0.1),
                               pdf_row=row_microfacet(0.11, 0.0))
    assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed


# ------------------------------------------------------------------------------------ energy / furnace
def _albedo_quadrature(theta, alpha, kd):
    wi = wi_at(theta)
    wr = wi * np.array([-1, -1, 1])
    peaks = [(wr, min(12 * alpha, np.pi)), (wr, 12 * alpha * max(wi[2], 0.02))] if alpha < 0.6 else []
    dirs, w, _ = refined_direction_grid(16, 8, peaks, n_fine=600)
    f = microfacet_f_ref(wi, dirs, alpha, kd)
    return (f * np.maximum(dirs[:, 2], 0)[:, None] * w[:, None]).sum(0)


@pytest.mark.plugin("microfacet", "sampling")
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


# ---------------------------------------------------------------------------------------- textures
def test_checkerboard_on_microfacet(ctx, queue):
    from textures.test_checkerboard_color import CHECKER_XML

    bsdf = bsdf_from_xml(CHECKER_XML.format(kind="microfacet", name="kd", extra=""))
    row = bsdf.pack()
    tex = bsdf.textures_table
    assert abs(row["microfacet"]["ks"] - (1 - 0.8)) < 1e-6
    _, _, alb = bsdf_pdf_eval_batch(ctx, queue, row, (0, 0, 1), [[0, 0, 1], [0, 0, 1]],
                                    uv=np.array([[0.1, 0.0], [0.35, 0.0]]), with_albedo=True, textures=tex)
    np.testing.assert_allclose(alb, [[0.8, 0.1, 0.1], [0.1, 0.2, 0.7]], rtol=1e-6)


def test_bsdf_is_delta_and_albedo(ctx, queue):
    """bsdf_albedo of every Nori BSDF at once (diffuse, mirror and dielectric beside microfacet), in one launch
    over an array of rows."""
    from .test_dielectric import row_dielectric
    from .test_mirror import row_mirror

    rows = np.array([row_diffuse((0.2, 0.3, 0.4)), row_mirror(), row_dielectric(), row_microfacet(0.2, 0.25)])
    pdf, f, alb = bsdf_pdf_eval_batch(ctx, queue, rows, (0, 0, 1), np.tile([0, 0, 1.0], (4, 1)),
                                      row_index=np.arange(4), with_albedo=True)
    np.testing.assert_allclose(alb, [[0.2, 0.3, 0.4], [1, 1, 1], [1, 1, 1], [0.25, 0.25, 0.25]], rtol=1e-6)


# ------------------------------------------------------------------------------------------- render
@pytest.mark.plugin("microfacet", "render")
def test_furnace_render(ctx, queue, tmp_path):
    """A microfacet plane in a constant environment of radiance 1 (path_mis) shows its directional albedo, the
    quadrature of its eval (to 0.3 %) at the camera's direction."""
    xml = ('<bsdf type="microfacet"><float name="alpha" value="0.2"/><color name="kd" value="0.1, 0.3, 0.2"/>'
           '</bsdf>')
    wi = furnace_wi()
    ref = albedo_quadrature(ctx, queue, plugin_row(xml), wi, lobe_grid(wi, 0.2))
    check_render_value(render_furnace_plane(tmp_path, xml, "nori"), ref, rel_tol=3e-3)
