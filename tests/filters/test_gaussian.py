"""Nori's and Mitsuba's gaussian filter (clrender/filters/gaussian.py, its table in kernels/filter.h): its offsets
follow its own tabulated pdf (chi-square of filter_sample on the device), its weighted samples reproduce the filter
(so an image converges to integral f L / integral f), and a rendered step edge is the filter's integral across it.
(The guided table the renderer samples: tests/test_filter_guide.py.)"""
import numpy as np
import pytest

from clrender.testing.plugin_checks import (FAMILIES, check_filter_edge_render, check_filter_offsets,
                                            check_filter_weights, chi2_test, filter_camera, filter_offsets)

CASES = {   # name: (rfilter type, its properties, scene format)
    "gaussian": ("gaussian", "", "nori"),
}


@pytest.mark.plugin("gaussian", "sampling")
@pytest.mark.parametrize("name", list(CASES))
def test_offsets_follow_their_pdf(ctx, queue, name):
    check_filter_offsets(ctx, queue, filter_camera(*CASES[name]), FAMILIES["filters"])


@pytest.mark.parametrize("name", list(CASES))
def test_weighted_samples_reproduce_the_filter(ctx, queue, name):
    check_filter_weights(ctx, queue, filter_camera(*CASES[name]), FAMILIES["filters"])


@pytest.mark.plugin("gaussian", "render")
@pytest.mark.parametrize("name", list(CASES))
def test_edge_render(tmp_path, name):
    check_filter_edge_render(tmp_path, *CASES[name])


def test_a_wrong_table_is_rejected(ctx, queue):
    """The chi-square above can fail: score gaussian offsets against a box filter's table."""
    cam = filter_camera(*CASES["gaussian"])
    out, _ = filter_offsets(ctx, queue, cam)
    r = cam.filter.radius
    edges = np.linspace(-r, r, 21)
    obs, _, _ = np.histogram2d(out[:, 0], out[:, 1], bins=[edges, edges])
    m = np.full(20, 1 / 20)
    assert not chi2_test(obs, np.outer(m, m) * len(out)).passed
