"""Nori's mirror (clrender/bsdfs/mirror.py, kernels/bsdfs/mirror.h) on the device: a delta BSDF, so its sampling is
checked exactly (direction, measure, weight, eta) rather than by a chi-square, and eval and pdf are zero."""
import numpy as np
import pytest

from clrender.testing.plugin_checks import (bsdf_pdf_eval_batch, bsdf_sample_batch, check_render_value, plugin_row,
                                            render_furnace_plane)


def row_mirror():
    return plugin_row('<bsdf type="mirror"/>')


@pytest.mark.plugin("mirror", "sampling")
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


@pytest.mark.plugin("mirror", "render")
def test_furnace_render(tmp_path):
    """A mirror plane in a constant environment of radiance 1 (path_mis) reflects exactly 1."""
    check_render_value(render_furnace_plane(tmp_path, '<bsdf type="mirror"/>', "nori"), 1.0)
