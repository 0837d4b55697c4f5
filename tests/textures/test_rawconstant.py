"""Mitsuba 3's rawconstant texture (clrender/textures/rawconstant.py, kernels/textures/rawconstant.h): its value
everywhere on the device and the host, its float view, its errors, and a rendered plane that shows it."""
import numpy as np
import pytest

from clrender.errors import SceneError
from clrender.scene import registry
from clrender.testing.plugin_checks import check_texture_render, texture_eval_batch


@pytest.mark.plugin("rawconstant", "eval")
def test_rawconstant_is_its_value_everywhere(ctx, queue):
    """Mitsuba 3.9.1's rawconstant: a <vector> as written (no colour conversion, no range check: negative and above
    1 stay), a <float> in every channel; a 3-D one read as a float and a value of another kind are errors."""
    vec = registry.instantiate("texture", "rawconstant", {"value": ("vector", [0.5, -2.0, 1.3])}, fmt="mitsuba")
    one = registry.instantiate("texture", "rawconstant", {"value": ("float", 0.25)}, fmt="mitsuba")
    uv = np.random.default_rng(3).uniform(-4, 4, size=(256, 2))
    dev_vec, dev_one = texture_eval_batch(ctx, queue, [vec, one], uv)
    np.testing.assert_array_equal(dev_vec, np.tile(np.float32([0.5, -2.0, 1.3]), (256, 1)))
    np.testing.assert_array_equal(dev_one, np.full((256, 3), 0.25, np.float32))
    np.testing.assert_array_equal(vec.eval(uv), np.tile([0.5, -2.0, 1.3], (256, 1)))
    assert one.float_view() is one
    with pytest.raises(SceneError, match="3-D value cannot fill a float parameter"):
        vec.float_view()
    with pytest.raises(SceneError, match="expected a <float> or a 3-D <vector>"):
        registry.instantiate("texture", "rawconstant", {"value": ("string", "x")}, fmt="mitsuba")
    with pytest.raises(SceneError, match="needs a \"value\""):
        registry.instantiate("texture", "rawconstant", {}, fmt="mitsuba")


@pytest.mark.plugin("rawconstant", "render")
def test_furnace_render(tmp_path):
    """A diffuse plane with a rawconstant reflectance in a constant environment of radiance 1 shows the value."""
    check_texture_render(tmp_path, '<texture type="rawconstant" name="reflectance"><vector name="value" '
                                   'value="0.2, 0.5, 0.7"/></texture>', "mitsuba")
