"""Mitsuba 3's cube (clrender/shapes/cube.py: a closed mesh, [-1, 1]^3): its geometry and uv as Mitsuba 3.9 gives them,
its sampling as an area light (a chi-square of the directions against the pdf it gives them, traced), and a rendered
furnace (shared set-up: shape_common.py)."""
import pytest

from .shape_common import check_shape_furnace_render, check_shape_sampling

SHAPE = ('<shape type="cube"><transform name="to_world"><scale value="0.5"/>'
         '<rotate z="1" angle="30"/></transform>{emitter}</shape>')


@pytest.mark.plugin("cube", "sampling")
def test_sampling_as_an_area_light(tmp_path, ctx, queue, kernels):
    check_shape_sampling(tmp_path, ctx, queue, kernels, SHAPE, (1.4, -0.3, 0.6), 0, seed=2004)


@pytest.mark.plugin("cube", "render")
def test_furnace_render(tmp_path):
    check_shape_furnace_render(tmp_path, SHAPE, (0.1, 0.2, 3.0), (0.1, 0.2, 0.5))
