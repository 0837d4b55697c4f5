"""Mitsuba 3's instance of a shapegroup (clrender/shapes/instance.py: flattened into world-space copies when the scene
is read): a rendered furnace of an instanced cube (shared set-up: shape_common.py). An instance holds no emitter
(refused, as in Mitsuba), so nothing of it is sampled: the coverage test lists that as its gap. Instancing's copies
and errors are tested in tests/test_mitsuba_shapes.py."""
import pytest

from .shape_common import check_shape_furnace_render

SHAPE = ('<shape type="shapegroup" id="g"><shape type="cube"><transform name="to_world"><scale value="0.5"/>'
         '</transform>{emitter}</shape></shape><shape type="instance"><ref id="g"/><transform name="to_world">'
         '<rotate z="1" angle="20"/><translate x="0.3"/></transform></shape>')


@pytest.mark.plugin("instance", "render")
def test_furnace_render(tmp_path):
    """The instanced cube's top face, moved and turned by the instance's to_world, shows its albedo."""
    check_shape_furnace_render(tmp_path, SHAPE, (0.35, 0.1, 3.0), (0.3, 0.05, 0.5))
