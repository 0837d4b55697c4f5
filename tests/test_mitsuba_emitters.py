"""Mitsuba 3 emitters (clrender/emitters: point, spot, directional, constant, envmap registered for Mitsuba files),
on the device through the kernels of tests/test_emitters.py.

* spot: Mitsuba's falloff (1 inside the beam, linear in angle to 0 at the cutoff) against closed-form values;
* directional and point: the irradiance / intensity as Mitsuba names them;
* envmap: lat-long lookup against a numpy reference, chi-square of the 2-D importance sampling against its pdf,
  weight = eval / pdf, pdf normalised over the sphere, and a furnace through path_mis (a constant map around a
  diffuse sphere: a·L on the sphere, L elsewhere) in which pdf and eval must agree for MIS to stay unbiased.
"""
import numpy as np
import pytest

import clrender
from clrender.errors import SceneError
from clrender.loader import load_scene
from clrender.pack import pack_scene
from clrender.scene import registry
from clrender.scene.transform import Transform
from clrender.testing.stats import compare_mean_to_value, compare_to_value
from clrender.textures.imagefile import read_image, write_rgbe

from test_emitters import HEADER, Dev, kernels, run_chi2, tris_obj, quad  # noqa: F401  (kernels: a fixture)


def mitsuba(type_name, **props):
    """A Mitsuba-format emitter made from code: props name=(tag, value)."""
    return registry.instantiate("emitter", type_name, props, fmt="mitsuba")


def device(tmp, ctx, queue, kernels, emitters, stem="s"):
    """A ground quad (for the scene bounds) lit by the given emitter objects, packed and on the device."""
    (tmp / "ground.obj").write_text(tris_obj(quad([0, 0, 0], [0, 0, 5], [5, 0, 0])))
    path = tmp / f"{stem}.xml"
    path.write_text(HEADER + '<mesh type="obj"><string name="filename" value="ground.obj"/></mesh>\n</scene>\n')
    scene = load_scene(path)
    scene.emitters.extend(emitters)
    return Dev(ctx, queue, kernels, pack_scene(scene))


def unit(v):
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# ------------------------------------------------------------------------------------------------ delta lights
def test_spot_falloff_closed_form(tmp_path, ctx, queue, kernels):
    pos = np.array([0.5, 3.0, -0.2])
    to_world = Transform.lookat(pos, [0.5, 0.0, -0.2], [0, 0, 1])
    spot = mitsuba("spot", intensity=("color", [2.0, 3.0, 4.0]), cutoff_angle=("float", 30.0),
                   beam_width=("float", 10.0), to_world=("transform", to_world))
    d = device(tmp_path, ctx, queue, kernels, [spot])
    # points at angle theta off the axis (straight down), at distance r from the light
    theta = np.radians([0.0, 5.0, 9.9, 10.1, 15.0, 20.0, 25.0, 29.9, 30.1, 45.0, 90.0, 120.0])
    expect = np.array([1, 1, 1, (30 - 10.1) / 20, 0.75, 0.5, 0.25, 0.1 / 20, 0, 0, 0, 0])
    phi = np.linspace(0, 2 * np.pi, len(theta), endpoint=False)
    leave = np.stack([np.sin(theta) * np.cos(phi), -np.cos(theta), np.sin(theta) * np.sin(phi)], axis=1)
    r = np.linspace(0.5, 4.0, len(theta))
    refs = (pos + leave * r[:, None]).astype(np.float32)
    s = d.sample(0, refs, np.zeros((len(theta), 2), np.float32))
    assert np.all(s["delta"] == 1) and np.all(s["pdf"] == 1)
    np.testing.assert_allclose(s["w"] * r[:, None] ** 2, expect[:, None] * [2.0, 3.0, 4.0], rtol=2e-3, atol=1e-5)
    np.testing.assert_allclose(spot.falloff(leave), expect, atol=1e-9)
    # defaults: cutoff 20, beam 15 (3/4 of the cutoff), intensity 1
    dflt = mitsuba("spot")
    assert (dflt.cutoff, dflt.beam_width) == (20.0, 15.0)
    np.testing.assert_allclose(dflt.falloff(unit([[0, 0, 1], [np.sin(np.radians(17.5)), 0,
                                                              np.cos(np.radians(17.5))]])), [1, 0.5])


def test_directional_irradiance_and_point_intensity(tmp_path, ctx, queue, kernels):
    rot = Transform.rotate([1, 0, 0], 90.0)     # local +z -> world -y: light travelling straight down
    lights = [mitsuba("directional", irradiance=("color", [1.0, 2.0, 3.0]), direction=("vector", [0.3, -1.0, 0.2])),
              mitsuba("directional", irradiance=("color", 5.0), to_world=("transform", rot)),
              mitsuba("point", intensity=("color", [3.0, 2.0, 1.0]), position=("point", [0.2, 2.0, 0.1])),
              mitsuba("point", to_world=("transform", Transform.translate([1.0, 1.5, -0.5])))]
    d = device(tmp_path, ctx, queue, kernels, lights)
    refs = np.array([[0.5, 0.0, 0.5], [1.0, 0.3, 2.0], [3.0, 0.1, 1.0]], np.float32)
    u = np.zeros((3, 2), np.float32)
    s = d.sample(0, refs, u)
    np.testing.assert_allclose(s["w"], np.broadcast_to([1, 2, 3], (3, 3)), rtol=1e-6)
    np.testing.assert_allclose(s["wi"], np.broadcast_to(-unit([0.3, -1.0, 0.2]), (3, 3)), atol=1e-6)
    s = d.sample(1, refs, u)
    np.testing.assert_allclose(s["w"], 5.0, rtol=1e-6)
    np.testing.assert_allclose(s["wi"], np.broadcast_to([0, 1, 0], (3, 3)), atol=1e-6)
    for e, pos, intensity in ((2, [0.2, 2.0, 0.1], [3, 2, 1]), (3, [1.0, 1.5, -0.5], [1, 1, 1])):
        s = d.sample(e, refs, u)
        r2 = ((refs - np.array(pos)) ** 2).sum(axis=1)
        np.testing.assert_allclose(s["w"] * r2[:, None], np.broadcast_to(intensity, (3, 3)), rtol=1e-4)


def test_delta_light_errors():
    with pytest.raises(SceneError, match="beam_width"):
        mitsuba("spot", cutoff_angle=("float", 10.0), beam_width=("float", 20.0))
    with pytest.raises(SceneError, match="either direction or to_world"):
        mitsuba("directional", direction=("vector", [0, 0, 1]), to_world=("transform", Transform()))
    with pytest.raises(SceneError, match="non-zero"):
        mitsuba("directional", direction=("vector", [0, 0, 0]))


# ---------------------------------------------------------------------------------------------------- envmap
def sky_image(w=24, h=12):
    """A small lat-long test map: a dim gradient, a bright warm patch and a black band (generated here)."""
    y, x = np.mgrid[0:h, 0:w]
    img = np.stack([0.2 + 0.3 * x / w, 0.3 + 0.2 * y / h, 0.5 - 0.3 * y / h], axis=-1)
    img[2:4, 5:8] = [40.0, 30.0, 10.0]
    img[8, :] = 0.0
    return img.astype(np.float32)


def write_exr(path, img):
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, {"RGB": np.ascontiguousarray(img, np.float32)}).write(str(path))


@pytest.fixture(scope="module")
def envmaps(tmp_path_factory, ctx, queue, kernels):
    tmp = tmp_path_factory.mktemp("envmap")
    write_exr(tmp / "sky.exr", sky_image())
    rot = Transform.rotate([0.3, 1.0, -0.2], 70.0)
    em = mitsuba("envmap", filename=("string", str(tmp / "sky.exr")), scale=("float", 1.5),
                 to_world=("transform", rot))
    return em, device(tmp, ctx, queue, kernels, [em])


def test_rgbe_reader_round_trip(tmp_path):
    img = sky_image()
    write_rgbe(tmp_path / "sky.hdr", img)
    back = read_image(tmp_path / "sky.hdr")
    # 8 mantissa bits shared by the three channels: each is within 1/128 of the largest one
    assert np.all(np.abs(back - img) <= img.max(axis=-1, keepdims=True) / 128 + 1e-7)


def test_envmap_lookup_matches_reference(envmaps):
    em, d = envmaps
    dirs = unit(np.random.default_rng(3).normal(size=(4000, 3))).astype(np.float32)
    out = d.environment(dirs)
    np.testing.assert_allclose(out[:, :3], em.eval(dirs), rtol=2e-4, atol=2e-5)
    # orientation: with the identity, +y is the top row of the image, -z is u = 0 (Mitsuba's convention)
    flat = em.data * 0
    assert flat.shape[1] == em.image.shape[1] + 1


def test_envmap_orientation_convention(tmp_path):
    img = np.zeros((5, 8, 3), np.float32)
    img[0] = [1, 0, 0]      # zenith row
    img[4] = [0, 0, 1]      # nadir row
    img[2, 0] = [0, 7, 0]   # the first pixel of the horizon, centred at u = 1/16
    write_exr(tmp_path / "o.exr", img)
    em = mitsuba("envmap", filename=("string", str(tmp_path / "o.exr")))
    np.testing.assert_allclose(em.eval([0, 1, 0]), [1, 0, 0], atol=1e-6)
    np.testing.assert_allclose(em.eval([0, -1, 0]), [0, 0, 1], atol=1e-6)
    phi = 2 * np.pi / 16    # u = atan2(x, -z) / 2pi
    np.testing.assert_allclose(em.eval([np.sin(phi), 0, -np.cos(phi)]), [0, 7, 0], atol=1e-5)


def test_envmap_chi2(envmaps):
    em, d = envmaps
    r = run_chi2(d, 0, np.zeros(3), 0, 300_000, 16, seed=77, n_tests=1)
    assert r.passed, r.message


def test_envmap_weight_and_normalisation(envmaps):
    em, d = envmaps
    n = 20_000
    s = d.sample(0, np.zeros(3), np.random.default_rng(5).random((n, 2), dtype=np.float32))
    ok = s["pdf"] > 0
    assert ok.mean() > 0.999
    np.testing.assert_allclose(s["pdf_again"][ok], s["pdf"][ok], rtol=1e-5)
    np.testing.assert_allclose(s["w"][ok] * s["pdf"][ok, None], s["eval"][ok], rtol=2e-4, atol=1e-6)
    np.testing.assert_allclose(s["eval"][ok], em.eval(s["wi"][ok]), rtol=2e-4, atol=2e-5)
    # the pdf integrates to 1 over the sphere (Monte Carlo with uniform directions)
    dirs = unit(np.random.default_rng(6).normal(size=(400_000, 3))).astype(np.float32)
    pdf = d.environment(dirs)[:, 3]
    assert pdf.mean() * 4 * np.pi == pytest.approx(1.0, abs=5 * pdf.std() * 4 * np.pi / np.sqrt(len(pdf)))


def test_envmap_errors(tmp_path):
    write_exr(tmp_path / "tiny.exr", np.ones((2, 2, 3), np.float32))
    with pytest.raises(SceneError, match="at least 2 x 3"):
        mitsuba("envmap", filename=("string", str(tmp_path / "tiny.exr")))
    with pytest.raises(SceneError, match="not found"):
        mitsuba("envmap", filename=("string", str(tmp_path / "missing.exr")))
    write_exr(tmp_path / "ok.exr", np.ones((4, 8, 3), np.float32))
    with pytest.raises(SceneError, match="rotation"):
        mitsuba("envmap", filename=("string", str(tmp_path / "ok.exr")),
                to_world=("transform", Transform.scale([2, 1, 1])))


def test_envmap_mis_furnace(tmp_path):
    """A constant map L around a diffuse sphere of albedo a (convex: no interreflection) through path_mis: a L
    on the sphere, L around it."""
    write_exr(tmp_path / "grey.exr", np.full((16, 32, 3), 0.8, np.float32))
    xml = ('<scene><integrator type="path_mis"/><camera type="perspective"><float name="fov" value="40"/>'
           '<transform name="toWorld"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>'
           '<integer name="width" value="8"/><integer name="height" value="8"/></camera>'
           '<mesh type="sphere"><float name="radius" value="1.2"/><bsdf type="diffuse">'
           '<color name="albedo" value="0.6"/></bsdf></mesh></scene>')
    (tmp_path / "furnace.xml").write_text(xml)
    scene = clrender.load_scene(tmp_path / "furnace.xml")
    scene.emitters.append(mitsuba("envmap", filename=("string", str(tmp_path / "grey.exr")), scale=("float", 2.0)))
    film = clrender.render(scene, spp=512, seed=3)
    L = 1.6
    centre = film.image[3:5, 3:5]          # on the sphere
    corner = film.image[0:1, 0:1]          # background
    assert np.allclose(corner, L, rtol=1e-5), corner
    assert abs(centre.mean() - 0.6 * L) < 0.02 * L, centre.mean()
    res = compare_mean_to_value(film, float(film.image.mean()), 0.01)   # sanity: the helper runs on this film
    assert res.passed
