"""Mitsuba 3's checkerboard texture (clrender/textures/checkerboard.py, kernels/textures/checkerboard.h): the pattern
on the host at hand-checked points and on the device against the host (through to_uv), its defaults, and a rendered
plane that shows the cell's colour at its uv."""
import numpy as np
import pytest

from clrender.scene import registry
from clrender.scene.transform import Transform
from clrender.testing.plugin_checks import check_texture_render, texture_eval_batch


@pytest.mark.plugin("checkerboard", "eval")
def test_checkerboard_pattern(ctx, queue):
    c0, c1 = [0.9, 0.1, 0.2], [0.05, 0.3, 0.7]
    t = registry.instantiate("texture", "checkerboard", {"color0": ("color", c0), "color1": ("color", c1),
                                                        "to_uv": ("transform", Transform.scale([3, 2, 1]))},
                             fmt="mitsuba")
    # [0, 1/2)^2 of st is color0; st = (3u, 2v)
    pts = np.array([[0.1 / 3, 0.1 / 2], [0.6 / 3, 0.1 / 2], [0.6 / 3, 0.6 / 2], [0.1 / 3, 0.6 / 2], [1.1 / 3, 0.1 / 2],
                    [-0.4 / 3, 0.1 / 2]])
    expect = np.array([c0, c1, c0, c1, c0, c1])
    np.testing.assert_allclose(t.eval(pts), expect)
    uv = np.concatenate([pts, np.random.default_rng(6).uniform(-3, 3, size=(4000, 2))])
    dev = texture_eval_batch(ctx, queue, [t], uv)[0]
    host = t.eval(uv)
    # points within float rounding of a cell edge may land either side
    st = uv @ t.to_uv[:, :2].T + t.to_uv[:, 2]
    frac = st - np.floor(st)
    clear = np.all(np.minimum(np.abs(frac - 0.5), np.minimum(frac, 1 - frac)) > 1e-5, axis=1)
    np.testing.assert_allclose(dev[clear], host[clear], atol=1e-7)
    np.testing.assert_allclose(dev[:6], expect, atol=1e-7)
    dflt = registry.instantiate("texture", "checkerboard", {}, fmt="mitsuba")
    np.testing.assert_allclose(dflt.eval([[0.2, 0.2], [0.7, 0.2]]), [[0.4] * 3, [0.2] * 3])


@pytest.mark.plugin("checkerboard", "render")
def test_furnace_render(tmp_path):
    """A diffuse plane with a checkerboard reflectance in a constant environment of radiance 1 shows the cell's
    colour at its uv."""
    check_texture_render(tmp_path, '<texture type="checkerboard" name="reflectance"><rgb name="color0" '
                                   'value="0.9, 0.1, 0.2"/><rgb name="color1" value="0.05, 0.3, 0.7"/></texture>',
                         "mitsuba")
