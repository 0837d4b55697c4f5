"""Nori's distant light (clrender/emitters/distant.py, kernels/emitters/distant.h; Mitsuba's `directional` is the
same plugin file) on the device: a delta light, so its sampling is checked exactly (direction, irradiance, pdf 1, a
far point outside the scene), and a rendered plane against the closed form. (Set-up: emitter_common.py.)"""
import numpy as np
import pytest

import analytic_scenes as A

from .emitter_common import _refs, check_noiseless_render


@pytest.mark.plugin("distant", "sampling")
def test_distant_light(scenes):
    d = scenes["delta"]
    rng = np.random.default_rng(8)
    refs = _refs(rng, 256, [-2.0, 0.0, -2.0], [2.0, 2.0, 2.0])
    s = d.sample(1, refs, rng.random((256, 2), dtype=np.float32))
    direction = np.array([0.4, -1.0, -0.5]) / np.linalg.norm([0.4, -1.0, -0.5])
    assert np.all(s["delta"] == 1) and np.all(s["pdf"] == 1) and np.all(np.isinf(s["dist"]))
    np.testing.assert_allclose(s["wi"], np.broadcast_to(-direction, (256, 3)), atol=1e-6)
    np.testing.assert_allclose(s["w"], np.broadcast_to([1, 0.95, 0.85], (256, 3)), rtol=1e-6)
    assert np.all(s["pdf_again"] == 0) and np.all(s["eval"] == 0)
    # the far point is outside the scene's bounding sphere
    c = d.b.info["bounds_center"][0]
    assert np.all(np.linalg.norm(s["p"] - c[:3], axis=1) > c[3])


@pytest.mark.plugin("distant", "render")
def test_distant_light_over_a_plane(tmp_path):
    """A distant light over a diffuse plane (path_mis): rho / pi x irradiance x |cos|; noiseless, so to float
    precision."""
    check_noiseless_render(tmp_path, A.distant_light_scene, A.distant_light_value())
