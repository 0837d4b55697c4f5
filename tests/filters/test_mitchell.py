"""Nori's and Mitsuba's Mitchell-Netravali filter and Mitsuba's catmullrom (clrender/filters/mitchell.py, its table in
kernels/filter.h; negative lobes: weights of either sign): its offsets follow its own tabulated pdf (chi-square of
filter_sample on the device), its weighted samples reproduce the filter (so an image converges to integral f L /
integral f), and a rendered step edge is the filter's integral across it. (The guided table the renderer samples:
tests/test_filter_guide.py.)"""
import pytest

from clrender.testing.plugin_checks import (FAMILIES, check_filter_edge_render, check_filter_offsets,
                                            check_filter_weights, filter_camera)

CASES = {   # name: (rfilter type, its properties, scene format)
    "mitchell": ("mitchell", "", "nori"),
    "catmullrom": ("catmullrom", "", "mitsuba"),
}


@pytest.mark.plugin("mitchell", "sampling")
@pytest.mark.parametrize("name", list(CASES))
def test_offsets_follow_their_pdf(ctx, queue, name):
    check_filter_offsets(ctx, queue, filter_camera(*CASES[name]), FAMILIES["filters"])


@pytest.mark.parametrize("name", list(CASES))
def test_weighted_samples_reproduce_the_filter(ctx, queue, name):
    check_filter_weights(ctx, queue, filter_camera(*CASES[name]), FAMILIES["filters"])


@pytest.mark.plugin("mitchell", "render")
@pytest.mark.parametrize("name", list(CASES))
def test_edge_render(tmp_path, name):
    check_filter_edge_render(tmp_path, *CASES[name])
