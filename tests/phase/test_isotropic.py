"""The isotropic phase function (clrender/phase/isotropic.py, kernels/phase/isotropic.h): its sampling against its
own density in the kernel (chi-square), 1 / (4 pi) everywhere, weight 1; rendered in tests/media/test_volpath.py
(the furnace and single scattering)."""
import numpy as np
import pytest

from .phase_common import chi2_of, eval_batch, phase_row

N = 1_000_000


@pytest.mark.plugin("isotropic", "sampling")
def test_sampling_matches_its_density(ctx, queue):
    row = phase_row("isotropic")
    wi = (0.6, -0.48, 0.64)
    r, exp, (wo, w, pdf) = chi2_of(ctx, queue, row, row, wi, N)
    assert r.passed, r.message
    assert abs(exp.sum() / N - 1) < 2e-3
    np.testing.assert_allclose(pdf, 1 / (4 * np.pi), rtol=1e-6)
    assert np.all(w == 1)
    np.testing.assert_allclose(eval_batch(ctx, queue, row, wi, wo[:1000]), 1 / (4 * np.pi), rtol=1e-6)
    # the test can fail: these samples against hg's forward density
    assert not chi2_of(ctx, queue, row, phase_row("hg", g=0.2), wi, N)[0].passed


@pytest.mark.plugin("isotropic", "render")
def test_furnace_render(tmp_path):
    """An isotropic, non-absorbing medium in a constant environment of radiance 1: every pixel is 1."""
    from media.media_common import furnace, render_xml
    from clrender.testing.stats import compare_to_value

    film = render_xml(tmp_path, furnace((2.0, 2.0, 2.0), '<phase type="isotropic"/>', spp=128))
    r = compare_to_value(film, 1.0)
    assert r.passed, f"{r.message}; image mean {film.image.mean(axis=(0, 1))}"
