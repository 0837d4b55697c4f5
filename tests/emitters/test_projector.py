"""Mitsuba 3's projection light (clrender/emitters/projector.py, kernels/emitters/projector.h) on the device: a delta
light, so its sampling is checked exactly (the inverse importance that makes a projected constant constant on the
plane z = 1, the frustum's edges from the fov and the texture's aspect ratio, a textured and a non-rigid to_world
against the host's formula), and rendered planes against the closed form. A textured projector against Mitsuba
3.9.1 itself is the twin scene tests/mitsuba/scenes/projector.xml (tests/test_mitsuba_twins.py). (Set-up:
emitter_common.py.)"""
import numpy as np
import pytest

import clrender
from clrender.emitters.emitter import LUMINANCE
from clrender.errors import SceneError
from clrender.scene.transform import Transform

from .emitter_common import device, mitsuba, write_exr

# A 10 x 5 image (aspect 2) of distinct texels, made here.
SLIDE = (np.arange(50, dtype=np.float32).reshape(5, 10, 1) * [0.02, 0.01, 0.03] + [0.1, 0.5, 0.2]).astype(np.float32)


TWO_SLIDES = """<scene version="3.0.0"><sensor type="perspective"/>
    <shape type="rectangle"/>
    <emitter type="projector">
        <texture type="bitmap" name="irradiance"><string name="filename" value="slide.exr"/>
            <string name="filter_type" value="nearest"/></texture>
        <float name="fov" value="20"/><string name="fov_axis" value="y"/>
        <transform name="to_world"><lookat origin="0, 3, 0" target="0, 0, 0" up="0, 0, 1"/></transform>
    </emitter>
    <emitter type="projector">
        <texture type="bitmap" name="irradiance"><string name="filename" value="slide.exr"/>
            <string name="filter_type" value="nearest"/></texture>
        <float name="fov" value="60"/><float name="scale" value="0.7"/>
        <transform name="to_world"><matrix value="1.3 0.2 0.1 0.4  0 0.8 -0.3 2.5  0.1 0 -1.1 0.3  0 0 0 1"/></transform>
    </emitter>
</scene>"""


@pytest.mark.plugin("projector", "sampling")
def test_projector_inverse_importance_and_frustum(tmp_path, ctx, queue, kernels):
    """On the plane z = 1 in front of the pinhole (rigid to_world), sample weight x cos = pi scale E everywhere in the
    rectangle |x| <= tan(fov_x / 2), |y| <= tan(fov_x / 2) / aspect, and 0 just outside it and behind the light; the
    weight follows 1 / z^2 along a ray. Delta: pdf 1, delta 1, wi toward the pinhole, no density, never seen."""
    pos = np.array([0.3, 2.0, -0.4])
    to_world = Transform.lookat(pos, [0.5, 0.0, -0.2], [0, 0, 1])
    E, scale = np.array([2.0, 1.0, 0.5]), 1.5
    proj = mitsuba("projector", irradiance=("color", E), scale=("float", scale), fov=("float", 50.0),
                     to_world=("transform", to_world))
    d = device(tmp_path, ctx, queue, kernels, [proj])
    m = to_world.matrix[:3, :3]
    t = np.tan(np.radians(25.0))
    rng = np.random.default_rng(7)
    inside = np.stack([rng.uniform(-t, t, 200), rng.uniform(-t, t, 200), np.ones(200)], axis=1)
    inside[:4, :2] = [[t, t], [-t, t], [t, -t], [-t, -t]]                  # the corners count (Mitsuba's <= 1)
    inside[:4, :2] *= 1 - 1e-5
    beside_x, beside_y = inside[:50].copy(), inside[50:100].copy()
    beside_x[:, 0] = np.sign(beside_x[:, 0]) * (1.002 * t + np.abs(beside_x[:, 0]))
    beside_y[:, 1] = np.sign(beside_y[:, 1]) * (1.002 * t + np.abs(beside_y[:, 1]))
    outside = np.concatenate([beside_x, beside_y, inside[100:150] * [1, 1, -1]])   # beside it; behind the light
    for local, lit in ((inside, True), (outside, False)):
        for depth in (1.0, 3.0):
            pts = pos + (local * depth) @ m.T
            s = d.sample(0, pts.astype(np.float32), np.zeros((len(pts), 2), np.float32))
            assert np.all(s["delta"] == 1) and np.all(s["pdf"] == 1)
            assert np.all(s["pdf_again"] == 0) and np.all(s["eval"] == 0)
            dist = np.linalg.norm(pts - pos, axis=1)
            np.testing.assert_allclose(s["dist"], dist, rtol=1e-5)
            np.testing.assert_allclose(s["wi"], (pos - pts) / dist[:, None], atol=1e-5)
            cos = depth / dist                                                   # the plane's normal is the axis
            got = s["w"] * cos[:, None] * depth ** 2
            np.testing.assert_allclose(got, np.pi * scale * E * np.ones((len(pts), 1)) if lit else 0.0,
                                       rtol=3e-4, atol=1e-6)
            np.testing.assert_allclose(s["w"], proj.weight(pts), rtol=3e-4, atol=1e-6)
    # the power that selection in proportion to power uses is the flux: the intensity w dist^2 integrated over the
    # sphere of directions (Monte Carlo, uniform directions; 5 standard errors)
    dirs = rng.normal(size=(200_000, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    s = d.sample(0, (pos + dirs).astype(np.float32), np.zeros((len(dirs), 2), np.float32))
    intensity = s["w"].astype(np.float64) @ LUMINANCE * 4 * np.pi     # dist = 1
    flux, err = intensity.mean(), intensity.std() / np.sqrt(len(dirs))
    assert abs(proj.selection_power(1.0, 0.0) - flux) < 5 * err, (proj.selection_power(1.0, 0.0), flux, err)
    assert err < 0.02 * flux


@pytest.mark.plugin("projector", "sampling")
def test_projector_texture_aspect_and_non_rigid_to_world(tmp_path, ctx, queue, kernels):
    """A 10 x 5 bitmap: the aspect ratio 2 makes the lit rectangle half as tall as wide; the fov on the y axis (the
    perspective sensor's fov_axis) and Mitsuba's uv (camera +x on the image's left, y down the image); and a
    to_world that scales and shears (Mitsuba's n = to_world (0, 0, 1), unnormalised) against the host's formula."""
    write_exr(tmp_path / "slide.exr", SLIDE)
    (tmp_path / "two.xml").write_text(TWO_SLIDES)
    a, b = clrender.load_scene(tmp_path / "two.xml").emitters
    assert a.texture.resolution() == (10, 5) and a.aspect == 2.0
    # fov 20 on y with aspect 2: tan(fov_x / 2) = 2 tan(10 degrees)
    np.testing.assert_allclose(np.tan(np.radians(a.fov) / 2), 2 * np.tan(np.radians(10.0)), rtol=1e-9)
    d = device(tmp_path, ctx, queue, kernels, [a, b])
    rng = np.random.default_rng(11)
    for i, em in enumerate((a, b)):
        local = np.stack([rng.uniform(-1.2, 1.2, 4000), rng.uniform(-0.7, 0.7, 4000), rng.uniform(-0.2, 3, 4000)], 1)
        local[:, :2] *= np.maximum(local[:, 2:], 0.0) * np.tan(np.radians(em.fov) / 2)
        pts = em.position + local @ np.linalg.inv(em.inverse_linear).T
        s = d.sample(i, pts.astype(np.float32), np.zeros((len(pts), 2), np.float32))
        expect = em.weight(pts)
        uv = em.uv(pts) * [10, 5]
        # away from the texel edges and the frustum's (float rounding may pick the neighbour there)
        clear = np.all(np.abs(uv - np.round(uv)) > 1e-3, axis=1) & (np.abs(local[:, 2]) > 1e-3)
        lit = em.lit(pts)
        assert (lit & clear).sum() > 1000 and (~lit & clear).sum() > 500
        np.testing.assert_allclose(s["w"][clear], expect[clear], rtol=3e-4, atol=1e-6)
        # every texel shows up: the whole image is projected, nothing else
        texel = np.floor(uv[lit & clear]).astype(int)
        assert len(np.unique(texel[:, 1] * 10 + texel[:, 0])) == 50
    # the lit rectangle of `a`: twice as wide as tall, at 3 below the light
    pts = np.array([[0.0, 0.0, 0.0], [2.9 * np.tan(np.radians(10.0)) * 2, 0, 0], [0, 0, 2.9 * np.tan(np.radians(10.0))],
                    [0, 0, 3.1 * np.tan(np.radians(10.0))]])
    np.testing.assert_array_equal(a.lit(pts), [True, True, True, False])
    np.testing.assert_array_equal(d.sample(0, pts.astype(np.float32), np.zeros((4, 2), np.float32))["w"][:, 0] > 0,
                                  [True, True, True, False])
    # Mitsuba's uv: the pixel (0, 0) of the image is at camera +x (the image's left from behind the light), +y
    corner = 2.9 * np.tan(np.radians(10.0))
    np.testing.assert_allclose(a.uv(a.position + np.array([2 * corner, corner, 3.0]) @ np.linalg.inv(a.inverse_linear).T),
                               [0.5 - 0.5 * 2.9 / 3, 0.5 - 0.5 * 2.9 / 3], rtol=1e-9)


PLANE = """<scene version="3.0.0"><integrator type="path"/>
    <sensor type="perspective"><float name="fov" value="80"/>
        <transform name="to_world"><lookat origin="0.2, -0.1, 2" target="0.2, -0.1, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/>
        </film></sensor>
    <shape type="rectangle"><transform name="to_world"><scale value="4"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
    <emitter type="projector">IRRADIANCE<float name="scale" value="1.5"/>FOV
        <transform name="to_world"><lookat origin="0.2, -0.1, 2" target="0.2, -0.1, 0" up="0, 1, 0"/></transform>
    </emitter>
</scene>"""


@pytest.mark.plugin("projector", "render")
@pytest.mark.parametrize("irradiance, fov, aspect", [
    ('<rgb name="irradiance" value="2, 1, 0.5"/>', '<float name="fov" value="60"/>', 1.0),
    ('<texture type="bitmap" name="irradiance"><string name="filename" value="flat.exr"/></texture>',
     '<float name="fov" value="40"/><string name="fov_axis" value="y"/>', 1.5),
], ids=["rgb", "flat 3x2 bitmap"])
def test_projector_on_a_plane(tmp_path, irradiance, fov, aspect):
    """A diffuse plane 2 below a constant projector, seen from the projector's pinhole: rho scale E / 2^2 (the plane
    receives pi scale E / z^2) in every pixel wholly inside the projected rectangle (its half-widths tan(fov_x / 2),
    tan(fov_x / 2) / aspect: the second case's fov is on y and its aspect the 3 x 2 image's), 0 in every pixel wholly
    outside; the pixels on its edges are left out. A delta light over a flat plane: noiseless, to float precision."""
    write_exr(tmp_path / "flat.exr", np.full((2, 3, 3), [2.0, 1.0, 0.5], np.float32))
    (tmp_path / "p.xml").write_text(PLANE.replace("IRRADIANCE", irradiance).replace("FOV", fov))
    scene = clrender.load_scene(tmp_path / "p.xml")
    film = clrender.render(scene, spp=8, seed=1)
    tx = np.tan(np.radians(scene.emitters[0].fov) / 2)
    half = np.array([tx, tx / aspect])                      # the lit rectangle's half-sizes (x, y) at depth 1
    edges = (1 - 2 * np.arange(33) / 32) * np.tan(np.radians(40.0))   # the camera's pixel edges at depth 1
    lo = np.minimum(np.abs(edges[:-1]), np.abs(edges[1:])) * (np.sign(edges[:-1]) == np.sign(edges[1:]))
    hi = np.maximum(np.abs(edges[:-1]), np.abs(edges[1:]))
    inside = (hi[None, :] < half[0]) & (hi[:, None] < half[1])                # (row, column)
    outside = (lo[None, :] > half[0]) | (lo[:, None] > half[1])
    assert inside.sum() > 100 and outside.sum() > 200
    value = np.array([0.6, 0.5, 0.4]) * 1.5 * np.array([2.0, 1.0, 0.5]) / 4.0
    img = film.image[..., :3]
    np.testing.assert_allclose(img[inside], np.broadcast_to(value, img[inside].shape), rtol=2e-4)
    assert np.all(img[outside] == 0)


def test_projector_errors(tmp_path):
    """Bad input names the file and line: an irradiance given twice, a texture under another name, a bad fov."""
    def load(body):
        (tmp_path / "e.xml").write_text(f'<scene version="3.0.0"><emitter type="projector">{body}</emitter></scene>')
        return clrender.load_scene(tmp_path / "e.xml")

    checker = '<texture type="checkerboard" name="NAME"/>'
    with pytest.raises(SceneError, match="both as a colour and as a texture"):
        load('<rgb name="irradiance" value="1"/>' + checker.replace("NAME", "irradiance"))
    with pytest.raises(SceneError, match="takes a texture named 'irradiance'"):
        load(checker.replace("NAME", "radiance"))
    with pytest.raises(SceneError, match=r"fov must be in \(0, 180\)"):
        load('<float name="fov" value="180"/>')
    with pytest.raises(SceneError, match="either 'fov' or 'focal_length'"):
        load('<float name="fov" value="30"/><string name="focal_length" value="20mm"/>')
    with pytest.raises(SceneError, match="scale must be non-negative"):
        load('<float name="scale" value="-1"/>')
    # defaults: irradiance 1, scale 1, focal length 50 mm (the perspective sensor's: a 35 mm film's diagonal)
    p = mitsuba("projector")
    assert p.scale == 1.0 and np.all(p.irradiance == 1.0) and p.aspect == 1.0
    np.testing.assert_allclose(p.fov, np.degrees(2 * np.arctan(np.hypot(36, 24) / 100 / np.sqrt(2))), rtol=1e-9)
