"""Nori's point light (clrender/emitters/point.py, kernels/emitters/point.h) on the device: a delta light, so its
sampling is checked exactly (the inverse-square law, power / 4 pi, no density for any direction), and a rendered
plane against the closed form. (Set-up: emitter_common.py.)"""
import numpy as np
import pytest

import analytic_scenes as A

from .emitter_common import check_noiseless_render


@pytest.mark.plugin("point", "sampling")
def test_point_light_inverse_square(scenes):
    d = scenes["delta"]
    pos = np.array([-1.0, 3.0, 2.0])
    power = np.array([120.0, 100.0, 80.0])
    dirs = np.random.default_rng(2).normal(size=(64, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    dist = np.geomspace(0.1, 100.0, 64)
    refs = (pos + dirs * dist[:, None]).astype(np.float32)
    s = d.sample(0, refs, np.random.default_rng(4).random((64, 2), dtype=np.float32))
    assert np.all(s["delta"] == 1) and np.all(s["pdf"] == 1)
    np.testing.assert_allclose(s["dist"], dist, rtol=1e-5)
    np.testing.assert_allclose(s["wi"], -dirs, atol=1e-5)
    np.testing.assert_allclose(s["p"], np.broadcast_to(pos, (64, 3)), atol=1e-5)
    np.testing.assert_allclose(s["w"] * dist[:, None] ** 2, np.broadcast_to(power / (4 * np.pi), (64, 3)),
                               rtol=1e-4)
    # a delta light has no density for any direction and is never seen by a ray
    assert np.all(s["pdf_again"] == 0) and np.all(s["eval"] == 0)
    np.testing.assert_allclose(d.b.emitters[0]["point"]["intensity"][:3], power / (4 * np.pi), rtol=1e-6)


@pytest.mark.plugin("point", "render")
def test_point_light_over_a_plane(tmp_path):
    """A point light over a diffuse plane (path_mis): rho / pi x power / (4 pi) x cos / d^2; noiseless, so to float
    precision."""
    check_noiseless_render(tmp_path, A.point_light_scene, A.point_light_value())
