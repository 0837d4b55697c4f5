"""Henyey-Greenstein (clrender/phase/hg.py, kernels/phase/hg.h): its sampling against its own density in the kernel
(chi-square, g from strongly backward to strongly forward, at two incident directions), the density against the
formula and its integral, weight = eval / pdf; its render is checked in tests/media/test_volpath.py (single
scattering against quadrature)."""
import numpy as np
import pytest

from .phase_common import chi2_of, eval_batch, phase_row

N = 1_000_000
GS = (-0.7, 0.0, 0.3, 0.9)
WIS = ((0.0, 0.0, 1.0), (0.6, -0.48, 0.64))
CASES = [(g, wi) for g in GS for wi in WIS]


def hg(g, cos):
    return (1 - g * g) / (4 * np.pi * (1 + g * g + 2 * g * cos) ** 1.5)


@pytest.mark.plugin("hg", "sampling")
@pytest.mark.parametrize("g,wi", CASES)
def test_sampling_matches_its_density(ctx, queue, g, wi):
    row = phase_row("hg", g=g)
    r, exp, (wo, w, pdf) = chi2_of(ctx, queue, row, row, wi, N, n_tests=len(CASES))
    assert r.passed, r.message
    assert abs(exp.sum() / N - 1) < 2e-3, f"the density integrates to {exp.sum() / N}"
    np.testing.assert_allclose(np.linalg.norm(wo, axis=1), 1, atol=3e-6)
    cos = wo @ np.asarray(wi)
    np.testing.assert_allclose(pdf, hg(g, cos), rtol=2e-3)      # the pdf it reports is the formula's
    np.testing.assert_allclose(w, 1, rtol=2e-5)                  # sampled exactly: eval / pdf = 1
    mean_cos = -cos.mean()                                       # the mean cosine to the forward direction is g
    assert abs(mean_cos - g) < 5 * np.sqrt(max(1 - g * g, 1e-3) / N) + 1e-3, (mean_cos, g)


@pytest.mark.plugin("hg", "sampling")
def test_eval_is_the_formula(ctx, queue):
    rng = np.random.default_rng(3)
    wo = rng.normal(size=(5000, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = np.array([0.0, 0.6, 0.8])
    for g in (-0.7, 0.3, 0.9):
        np.testing.assert_allclose(eval_batch(ctx, queue, phase_row("hg", g=g), wi, wo), hg(g, wo @ wi), rtol=1e-4)


def test_a_wrong_density_fails(ctx, queue):
    """The test can fail: g = 0.3's samples against g = 0.35's density, and g = 0.9's against isotropic's."""
    wi = WIS[1]
    assert not chi2_of(ctx, queue, phase_row("hg", g=0.3), phase_row("hg", g=0.35), wi, N)[0].passed
    assert not chi2_of(ctx, queue, phase_row("hg", g=0.9), phase_row("isotropic"), wi, N)[0].passed


@pytest.mark.plugin("hg", "render")
@pytest.mark.parametrize("g", [-0.7, 0.6])
def test_single_scattering_render_against_quadrature(tmp_path, g):
    """hg in a rendered medium: a slab lit by a directional light, max_depth 2 (one scattering event), each pixel
    against the single-scattering integral with hg's density at the angle between light and camera."""
    from media.media_common import render_xml, single_scattering_slab, single_scattering_value
    from clrender.testing.stats import compare_to_value

    phase = f'<phase type="hg"><float name="g" value="{g}"/></phase>'
    args = ((1.2, 0.8, 0.4), 0.8, phase, 0.5, 50.0, (2.0, 2.0, 2.0))
    expected = single_scattering_value(args[0], args[1], lambda c: hg(g, c), *args[3:])
    film = render_xml(tmp_path, single_scattering_slab(*args, spp=1024))
    r = compare_to_value(film, expected)
    assert r.passed, f"{r.message}; image mean {film.image.mean(axis=(0, 1))}, expected {expected}"
