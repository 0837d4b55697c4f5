"""Mitsuba 3's null BSDF (no surface: clrender/bsdfs/null.py, the mask of kernels/bsdfs/mask.h at opacity 0) on the
device: a delta BSDF, so its sampling is checked exactly (every sample passes straight through, as a discrete event
of weight 1 and eta 1, from either side), eval and pdf are zero, and a null plane in a furnace renders the
environment behind it. (Paths that meet only null surfaces are checked against Mitsuba in
tests/test_mitsuba_integrators.py::test_null_bsdf_and_paths_that_meet_no_surface.)"""
import numpy as np
import pytest

from clrender.testing.plugin_checks import (bsdf_pdf_eval_batch, bsdf_sample_batch, check_render_value, mitsuba_bsdf,
                                            pack_rows, render_furnace_plane)


@pytest.mark.plugin("null", "sampling")
def test_every_sample_passes_straight_through(ctx, queue):
    rng = np.random.default_rng(8)
    wi = rng.normal(size=(4000, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wi32 = wi.astype(np.float32)
    rows = pack_rows(mitsuba_bsdf("null"))   # a composite: the mask's row, then its (unreached) child's
    s = bsdf_sample_batch(ctx, queue, rows, wi32, len(wi), 2)
    np.testing.assert_allclose(s.wo, -wi32, rtol=0, atol=1e-7)
    assert np.all(s.weight == 1) and np.all(s.measure == 1) and np.all(s.eta == 1)
    pdf, f = bsdf_pdf_eval_batch(ctx, queue, rows, wi, s.wo)
    assert np.all(pdf == 0) and np.all(f == 0)


@pytest.mark.plugin("null", "render")
def test_furnace_render(tmp_path):
    """A null plane in a constant environment of radiance 1 (Mitsuba's path) shows exactly the environment."""
    check_render_value(render_furnace_plane(tmp_path, '<bsdf type="null"/>'), 1.0)
