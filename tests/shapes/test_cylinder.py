"""Mitsuba 3's cylinder (clrender/shapes/cylinder.py: an open tube mesh from p0 to p1): its geometry and uv as Mitsuba
3.9 gives them, its sampling as an area light (a chi-square of the directions against the pdf it gives them, traced),
and a rendered furnace (shared set-up: shape_common.py)."""
import numpy as np
import pytest

from clrender.shapes.cylinder import axis_frame, cylinder_mesh

from .shape_common import check_shape_furnace_render, check_shape_sampling, surface_points

SHAPE = ('<shape type="cylinder"><point name="p0" value="0, 0, -0.6"/>'
         '<point name="p1" value="0, 0.2, 0.8"/><float name="radius" value="0.4"/>{emitter}</shape>')


def test_cylinder_is_mitsubas():
    p0, p1, r = np.array([0.5, -1.0, 2.0]), np.array([1.0, 1.0, 0.0]), 0.3
    m = cylinder_mesh(p0, p1, r)
    p, uv, ns, ng = surface_points(m)
    axis = (p1 - p0) / np.linalg.norm(p1 - p0)
    s, t = axis_frame(axis)
    np.testing.assert_allclose([s @ t, s @ axis, t @ axis], 0, atol=1e-12)
    np.testing.assert_allclose(np.cross(s, t), axis, atol=1e-12)
    d = p - p0
    z = d @ axis / np.linalg.norm(p1 - p0)
    radial = d - np.outer(d @ axis, axis)
    rr = np.linalg.norm(radial, axis=1)
    phi = np.mod(np.arctan2(radial @ t, radial @ s), 2 * np.pi)
    assert np.all((rr <= r + 1e-6) & (rr > r * (1 - 2e-5)))
    np.testing.assert_allclose(uv[:, 1], z, atol=1e-6)
    du = np.abs(uv[:, 0] - phi / (2 * np.pi))
    assert np.minimum(du, 1 - du).max() < 1e-5
    # shading normals: radial, outward; face normals outward too
    np.testing.assert_allclose(ns, radial / rr[:, None], atol=1e-5)
    assert np.all(np.einsum("ij,ij->i", ng, radial) > 0)


def test_default_cylinder_frame_is_identity():
    s, t = axis_frame(np.array([0.0, 0.0, 1.0]))
    np.testing.assert_allclose(s, [1, 0, 0])
    np.testing.assert_allclose(t, [0, 1, 0])


@pytest.mark.plugin("cylinder", "sampling")
def test_sampling_as_an_area_light(tmp_path, ctx, queue, kernels):
    check_shape_sampling(tmp_path, ctx, queue, kernels, SHAPE, (1.3, 0.5, 0.2), 0, seed=2003)


@pytest.mark.plugin("cylinder", "render")
def test_furnace_render(tmp_path):
    check_shape_furnace_render(tmp_path, SHAPE, (3.0, 0.1, 0.1), (0.4, 0.1, 0.1))
