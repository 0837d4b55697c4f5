"""Mitsuba 3's disk (clrender/shapes/disk.py: a fan mesh of the unit disk at z = 0 facing +z): its geometry and uv as
Mitsuba 3.9 gives them, its sampling as an area light (a chi-square of the directions against the pdf it gives them,
traced), and a rendered furnace (shared set-up: shape_common.py)."""
import numpy as np
import pytest

from clrender.shapes.disk import disk_mesh

from .shape_common import check_shape_furnace_render, check_shape_sampling, surface_points

SHAPE = ('<shape type="disk"><transform name="to_world"><scale value="0.9"/>'
         '<translate z="-0.5"/></transform>{emitter}</shape>')


def test_disk_is_mitsubas():
    m = disk_mesh()
    p, uv, ns, ng = surface_points(m)
    r = np.hypot(p[:, 0], p[:, 1])
    phi = np.mod(np.arctan2(p[:, 1], p[:, 0]), 2 * np.pi)
    assert np.all(r <= 1 + 1e-6) and np.all(p[:, 2] == 0)
    np.testing.assert_allclose(ng[:, 2], 1)
    # uv = (r, phi / 2pi): within the tessellation's error (a sector spans 2pi / 512)
    assert np.abs(uv[:, 0] - r).max() < 2e-4
    dv = np.abs(uv[:, 1] - phi / (2 * np.pi))
    dv = np.minimum(dv, 1 - dv)   # the seam
    assert dv.max() < 1.0 / 512
    area = 0.5 * np.linalg.norm(np.cross(*(m.positions[m.faces][:, 1:] - m.positions[m.faces][:, :1]).transpose(1, 0, 2)),
                                axis=1).sum()
    assert area == pytest.approx(np.pi, rel=5e-5)


@pytest.mark.plugin("disk", "sampling")
def test_sampling_as_an_area_light(tmp_path, ctx, queue, kernels):
    check_shape_sampling(tmp_path, ctx, queue, kernels, SHAPE, (0.6, 0.2, 0.7), 0, seed=2002)


@pytest.mark.plugin("disk", "render")
def test_furnace_render(tmp_path):
    check_shape_furnace_render(tmp_path, SHAPE, (1.5, 1.0, 2.0), (0.1, 0.2, -0.5))
