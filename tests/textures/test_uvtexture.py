"""ETH Nori's uvtexture (clrender/textures/uvtexture.py, kernels/textures/uvtexture.h): the kernel's colour at uv
against the host's formula (the ripple, the fractional part with C's fmod sign, blue 0.5) and at hand-checked
points, and a rendered plane that shows the colour at its uv."""
import numpy as np
import pytest

from clrender.scene import registry
from clrender.testing.plugin_checks import check_texture_render, texture_eval_batch


@pytest.mark.plugin("uvtexture", "eval")
def test_device_matches_the_formula(ctx, queue):
    tex = registry.instantiate("texture", "uvtexture", {})
    rng = np.random.default_rng(12)
    uv = np.concatenate([rng.uniform(-2.5, 2.5, (5000, 2)),
                         [[0.0, 0.0], [0.25, 0.5], [0.5, 1 / 32], [-0.25, 1.75], [1 / 32, 1 / 32]]])
    (got,) = texture_eval_batch(ctx, queue, [tex], uv)
    np.testing.assert_allclose(got, tex.eval(uv), rtol=2e-5, atol=2e-6)
    # by hand: u in red and v in green (fractional part, sign dropped), rippled by +-20 % with period 1/8, blue 0.5
    # (sin 16 pi u = 0 at u = 0.5, cos 16 pi u = 0 at u = 1/32, sin 16 pi v = 1 at v = 1/32)
    np.testing.assert_allclose(got[-5:], [[0.0, 0.0, 0.5], [0.25, 0.5, 0.5], [0.5, (1 - 0.2) / 32, 0.5],
                                          [0.25, 0.75, 0.5], [(1 - 0.2) / 32, 1 / 32, 0.5]], atol=2e-6)


@pytest.mark.plugin("uvtexture", "render")
def test_furnace_render(tmp_path):
    """A diffuse plane with a uvtexture albedo in a constant environment of radiance 1 shows the colour at its uv."""
    check_texture_render(tmp_path, '<texture type="uvtexture" name="albedo"/>')
