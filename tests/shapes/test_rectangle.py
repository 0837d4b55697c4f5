"""Mitsuba 3's rectangle (clrender/shapes/rectangle.py: a two-triangle mesh, [-1, 1]^2 at z = 0 facing +z): its geometry
and uv as Mitsuba 3.9 gives them, its sampling as an area light (a chi-square of the directions against the pdf it
gives them, traced), and a rendered furnace (shared set-up: shape_common.py)."""
import numpy as np
import pytest

from clrender.shapes.rectangle import rectangle_mesh

from .shape_common import check_shape_furnace_render, check_shape_sampling, surface_points

SHAPE = ('<shape type="rectangle"><transform name="to_world"><scale x="1.5" y="0.8"/>'
         '<rotate x="1" angle="20"/></transform>{emitter}</shape>')


def test_rectangle_is_mitsubas():
    p, uv, ns, ng = surface_points(rectangle_mesh())
    assert np.all(np.abs(p[:, :2]) <= 1) and np.all(p[:, 2] == 0)
    np.testing.assert_allclose(uv, (p[:, :2] + 1) / 2, atol=1e-6)
    np.testing.assert_allclose(ng, np.tile([0, 0, 1], (len(ng), 1)), atol=1e-12)


@pytest.mark.plugin("rectangle", "sampling")
def test_sampling_as_an_area_light(tmp_path, ctx, queue, kernels):
    check_shape_sampling(tmp_path, ctx, queue, kernels, SHAPE, (0.3, -0.4, 1.2), 0, seed=2001)


@pytest.mark.plugin("rectangle", "render")
def test_furnace_render(tmp_path):
    check_shape_furnace_render(tmp_path, SHAPE, (0.4, -2.0, 3.0), (0.2, 0.1, 0.0))
