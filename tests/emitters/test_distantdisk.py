"""Nori's distantdisk (a sun: radiance from a cone of directions, clrender/emitters/distantdisk.py,
kernels/emitters/distantdisk.h) on the device: chi-square of its sampled directions against its own pdf (cones of
10, 60 and 180 degrees), weight == eval / pdf per sample, the environment's radiance and pdf with a constant sky
beside it, its axis, and a rendered plane lit by it against the irradiance of a spherical cap. (Set-up:
emitter_common.py.)"""
import numpy as np
import pytest

import analytic_scenes as A
import clrender
from clrender.testing.stats import compare_to_value

from .emitter_common import SUN_ROTATE, check_chi2_case, check_weight_case


@pytest.mark.plugin("distantdisk", "sampling")
@pytest.mark.parametrize("case", ["distantdisk-10", "distantdisk-60", "distantdisk-180"])
def test_chi2_emitter_sampling(scenes, case):
    check_chi2_case(scenes, case)


@pytest.mark.parametrize("case", ["disk10", "disk180"])
def test_weight_is_eval_over_pdf(scenes, case):
    check_weight_case(scenes, case)


def test_environment_sum_and_pdf(scenes):
    d = scenes["sun"]
    rng = np.random.default_rng(12)
    dirs = rng.normal(size=(20_000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    axis = np.array([-0.45, 0.75, 0.5]) / np.linalg.norm([-0.45, 0.75, 0.5])
    # add directions inside the 6 degree sun
    near = axis + 0.04 * rng.normal(size=(5000, 3))
    dirs = np.concatenate([dirs, near / np.linalg.norm(near, axis=1, keepdims=True)]).astype(np.float32)
    out = d.environment(dirs)
    cos = dirs @ axis
    inside = cos >= np.cos(np.radians(6.0))
    keep = np.abs(cos - np.cos(np.radians(6.0))) > 1e-5   # float32 at the rim
    assert inside.sum() > 1000
    sky = np.array([0.12, 0.15, 0.2])
    expect_L = sky + np.where(inside[:, None], 50.0, 0.0)
    np.testing.assert_allclose(out[keep, :3], expect_L[keep], rtol=1e-5)
    cone_pdf = 1 / (2 * np.pi * (1 - np.cos(np.radians(6.0))))
    expect_pdf = (1 / (4 * np.pi) + np.where(inside, cone_pdf, 0.0)) / 2
    np.testing.assert_allclose(out[keep, 3], expect_pdf[keep], rtol=1e-4)
    # delta and area lights add nothing to escaping rays
    out = scenes["delta"].environment(dirs[:100])
    assert np.all(out == 0)


def test_distantdisk_axis_points_toward_the_light(scenes):
    """The sun scenes assume toWorld turns local +z toward the light (scenes/README.md)."""
    row = scenes["sun"].b.emitters[0]
    axis = row["distantdisk"]["frame"][2][:3]
    np.testing.assert_allclose(axis, np.array([-0.45, 0.75, 0.5]) / np.linalg.norm([-0.45, 0.75, 0.5]), atol=1e-4)
    s = scenes["sun"].sample(0, [0, 1, 0], np.random.default_rng(0).random((4096, 2), dtype=np.float32))
    ang = np.degrees(np.arccos(np.clip(s["wi"] @ axis, -1, 1)))
    assert ang.max() <= 6.0 + 1e-3 and ang.max() > 5.5
    frame = row["distantdisk"]["frame"][:, :3]
    np.testing.assert_allclose(frame @ frame.T, np.eye(3), atol=1e-6)


@pytest.mark.plugin("distantdisk", "render")
def test_sun_over_a_plane(tmp_path):
    """A diffuse plane (albedo rho, normal +z) under a sun of radiance L and half-angle 10 degrees whose axis is alpha
    from the normal (alpha + 10 < 90: the whole cap above the horizon): irradiance pi L sin^2(10) cos(alpha), so each
    pixel is rho L sin^2(10) cos(alpha) (path_mis, 4096 spp, per pixel)."""
    L = np.array([2.0, 3.0, 4.0])
    xml = (f'<scene><integrator type="path_mis"/>{A.camera()}{A.plane_mesh(tmp_path / "plane.obj")}'
           f'<emitter type="distantdisk"><color name="radiance" value="2, 3, 4"/><float name="thetaA" value="10"/>'
           f'{SUN_ROTATE}</emitter></scene>')
    (tmp_path / "s.xml").write_text(xml)
    axis = np.array([-0.45, 0.75, 0.5]) / np.linalg.norm([-0.45, 0.75, 0.5])   # SUN_ROTATE turns +z to it
    film = clrender.render(clrender.load_scene(tmp_path / "s.xml"), spp=4096, seed=1)
    ref = A.RHO * L * np.sin(np.radians(10.0)) ** 2 * axis[2]
    res = compare_to_value(film, ref, 0.01)
    assert res.passed, (res.message, film.image[0, 0], ref)
