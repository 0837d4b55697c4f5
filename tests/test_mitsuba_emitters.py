"""Mitsuba 3 emitters (clrender/emitters: point, spot, directional, constant, envmap registered for Mitsuba files),
on the device through the kernels of tests/emitters/emitter_common.py.

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
from clrender.device.layout import NONE
from clrender.pack import pack_scene, selection_cdf
from clrender.scene import registry
from clrender.scene.transform import Transform
from clrender.testing.stats import compare_films, compare_mean_to_value
from scipy import stats
from clrender.textures.imagefile import read_image, write_rgbe

from emitters.emitter_common import HEADER, Dev, kernels, run_chi2, tris_obj, quad  # noqa: F401  (kernels: a fixture)


def mitsuba(type_name, **props):
    """A Mitsuba-format emitter made from code: props name=(tag, value)."""
    return registry.instantiate("emitter", type_name, props, fmt="mitsuba")


def device(tmp, ctx, queue, kernels, emitters, stem="s", selection="uniform"):
    """A ground quad (for the scene bounds) lit by the given emitter objects, packed and on the device."""
    (tmp / "ground.obj").write_text(tris_obj(quad([0, 0, 0], [0, 0, 5], [5, 0, 0])))
    path = tmp / f"{stem}.xml"
    path.write_text(HEADER + '<mesh type="obj"><string name="filename" value="ground.obj"/></mesh>\n</scene>\n')
    scene = load_scene(path)
    scene.emitters.extend(emitters)
    return Dev(ctx, queue, kernels, pack_scene(scene, emitter_selection=selection))


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


SPOT_WITH_TEXTURE = """<scene version="3.0.0">
    <sensor type="perspective"><transform name="to_world"><lookat origin="0, 4, 4" target="0, 0, 0" up="0, 1, 0"/>
        </transform><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film>
    </sensor>
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="4"/></transform>
    </shape>
    <emitter type="spot">
        <rgb name="intensity" value="2, 3, 4"/>
        <float name="cutoff_angle" value="40"/>
        <float name="beam_width" value="25"/>
        <texture type="checkerboard" name="texture">
            <rgb name="color0" value="0.9, 0.5, 0.1"/><rgb name="color1" value="0.1, 0.2, 0.7"/>
            <transform name="to_uv"><scale x="3" y="2"/></transform>
        </texture>
        <transform name="to_world"><lookat origin="0.3, 3, -0.2" target="0.3, 0, -0.2" up="0, 0, 1"/></transform>
    </emitter>
</scene>"""


def test_spot_projects_its_texture_as_mitsuba(tmp_path, ctx, queue, kernels):
    """Mitsuba 3.9.1's spot with a `texture`: the intensity times the texture at direction_to_uv of the local direction
    (0.5 + 0.5 (x, y) / (z tan cutoff)); outside the cone, nothing (and no lookup)."""
    (tmp_path / "spot.xml").write_text(SPOT_WITH_TEXTURE)
    spot = next(e for e in clrender.load_scene(tmp_path / "spot.xml").emitters if type(e).__name__ == "SpotEmitter")
    assert spot.texture is not None
    d = device(tmp_path, ctx, queue, kernels, [spot])
    rng = np.random.default_rng(3)
    theta = np.radians(rng.uniform(0.0, 45.0, 400))
    phi = rng.uniform(0.0, 2 * np.pi, 400)
    leave = np.stack([np.sin(theta) * np.cos(phi), -np.cos(theta), np.sin(theta) * np.sin(phi)], axis=1)
    r = rng.uniform(0.5, 3.0, 400)
    refs = (spot.position + leave * r[:, None]).astype(np.float32)
    s = d.sample(0, refs, np.zeros((400, 2), np.float32))
    expect = spot.falloff(leave)[:, None] * spot.texture.eval(spot.uv(leave)) * [2.0, 3.0, 4.0]
    inside = spot.falloff(leave) > 0
    assert inside.sum() > 200 and (~inside).sum() > 20
    # away from the checker edges (float rounding of uv may pick the other square there)
    st = spot.uv(leave) * [3, 2]
    clear = np.all(np.abs(st * 2 - np.round(st * 2)) > 1e-3, axis=1)
    np.testing.assert_allclose((s["w"] * r[:, None] ** 2)[clear], expect[clear], rtol=2e-3, atol=1e-5)
    # the texture is what varies: both colours show up inside the cone
    assert len(np.unique(np.round(expect[inside & clear, 0], 6))) > 5


def test_spot_texture_must_be_nested_by_its_name(tmp_path):
    (tmp_path / "s.xml").write_text(SPOT_WITH_TEXTURE.replace('name="texture"', 'name="intensity"'))
    with pytest.raises(SceneError, match="takes a texture named 'texture'"):
        clrender.load_scene(tmp_path / "s.xml")


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


def test_emitter_defaults_are_mitsubas(tmp_path):
    """Every Mitsuba emitter defaults its strength to 1 (mi.load_dict of each prints UniformSpectrum 1): an area
    light written without a radiance (once an error here) is seen as exactly 1."""
    xml = ('<scene version="3.0.0"><sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" '
           'target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm"><integer name="width" value="4"/>'
           '<integer name="height" value="4"/><rfilter type="box"/></film></sensor>'
           '<shape type="sphere"><float name="radius" value="3"/><emitter type="area"/></shape></scene>')
    (tmp_path / "s.xml").write_text(xml)
    scene = clrender.load_scene(tmp_path / "s.xml")
    film = clrender.render(scene, spp=4, seed=1)
    np.testing.assert_allclose(film.image, 1.0, rtol=1e-6)
    for kind, field in (("point", "power"), ("spot", "intensity"), ("directional", "irradiance"),
                        ("constant", "radiance")):
        value = getattr(mitsuba(kind), field)
        np.testing.assert_allclose(value, 4 * np.pi if kind == "point" else 1.0, err_msg=kind)


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


def write_rgbe_rle(path, img):
    """Radiance's run-length scanlines (each component in turn; runs of equal bytes, literals otherwise)."""
    from clrender.textures.imagefile import write_rgbe

    write_rgbe(path, img)          # flat: reuse its header and RGBE bytes
    data = path.read_bytes()
    head_end = data.index(b"+X") + data[data.index(b"+X"):].index(b"\n") + 1
    h, w = img.shape[:2]
    px = np.frombuffer(data[head_end:], np.uint8).reshape(h, w, 4)
    out = bytearray(data[:head_end])
    for y in range(h):
        out += bytes([2, 2, w >> 8, w & 255])
        for c in range(4):
            row, x = px[y, :, c], 0
            while x < w:
                run = 1
                while x + run < w and run < 127 and row[x + run] == row[x]:
                    run += 1
                if run >= 3:
                    out += bytes([128 + run, row[x]])
                    x += run
                else:
                    n = 1
                    while x + n < w and n < 128 and not (x + n + 2 < w and row[x + n] == row[x + n + 1] == row[x + n + 2]):
                        n += 1
                    out += bytes([n]) + bytes(row[x:x + n])
                    x += n
    path.write_bytes(bytes(out))


def test_rgbe_run_length_scanlines(tmp_path):
    img = sky_image(w=24, h=12)
    write_rgbe(tmp_path / "flat.hdr", img)
    write_rgbe_rle(tmp_path / "rle.hdr", img)
    assert (tmp_path / "rle.hdr").stat().st_size < (tmp_path / "flat.hdr").stat().st_size
    np.testing.assert_array_equal(read_image(tmp_path / "rle.hdr"), read_image(tmp_path / "flat.hdr"))
    (tmp_path / "bad.hdr").write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 2 +X 2\n" + bytes(16))
    with pytest.raises(SceneError, match="32-bit_rle_xyze"):
        read_image(tmp_path / "bad.hdr")


def test_envmap_lookup_matches_reference(envmaps):
    em, d = envmaps
    dirs = unit(np.random.default_rng(3).normal(size=(4000, 3))).astype(np.float32)
    out = d.environment(dirs)
    np.testing.assert_allclose(out[:, :3], em.eval(dirs), rtol=2e-4, atol=2e-5)
    # the map is periodic in u: directions either side of the seam (u = 0, local -z) see nearly the same radiance
    eps = 1e-4
    local = np.array([[np.sin(eps), 0.3, -np.cos(eps)], [np.sin(-eps), 0.3, -np.cos(-eps)]])
    seam = d.environment((local @ em.to_world.T).astype(np.float32))[:, :3]
    np.testing.assert_allclose(seam[0], seam[1], rtol=1e-2)


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


def test_small_envmaps_are_padded(tmp_path, ctx, queue, kernels):
    """Maps below 2 x 3 pixels grow by repeating their last column and row (Mitsuba 3.9.1's Bitmap::pad_to): a 1 x 1
    map is a constant sky, on the device too, and the padded map's sampling passes chi-square against its pdf."""
    write_exr(tmp_path / "one.exr", np.full((1, 1, 3), [0.5, 1.0, 2.0], np.float32))
    one = mitsuba("envmap", filename=("string", str(tmp_path / "one.exr")))
    dirs = unit(np.random.default_rng(8).normal(size=(2000, 3))).astype(np.float32)
    env = device(tmp_path, ctx, queue, kernels, [one], stem="one").environment(dirs)
    np.testing.assert_allclose(env[:, :3], np.broadcast_to([0.5, 1.0, 2.0], (len(dirs), 3)), rtol=1e-5)
    row = np.array([[[4.0, 0.2, 0.1], [0.1, 0.3, 3.0]]], np.float32)   # 1 row, 2 columns
    write_exr(tmp_path / "row.exr", row)
    write_exr(tmp_path / "padded.exr", np.repeat(row, 3, axis=0))
    small = mitsuba("envmap", filename=("string", str(tmp_path / "row.exr")))
    padded = mitsuba("envmap", filename=("string", str(tmp_path / "padded.exr")))
    np.testing.assert_array_equal(small.eval(dirs), padded.eval(dirs))
    d = device(tmp_path, ctx, queue, kernels, [small], stem="row")
    np.testing.assert_allclose(d.environment(dirs)[:, :3], padded.eval(dirs), rtol=2e-4, atol=2e-5)
    r = run_chi2(d, 0, np.zeros(3), 0, 200_000, 16, seed=78, n_tests=1)
    assert r.passed, r.message
    pdf = d.environment(unit(np.random.default_rng(9).normal(size=(400_000, 3))).astype(np.float32))[:, 3]
    assert pdf.mean() * 4 * np.pi == pytest.approx(1.0, abs=5 * pdf.std() * 4 * np.pi / np.sqrt(len(pdf)))


@pytest.mark.parametrize("h, w", [(1, 1), (1, 2), (2, 1), (2, 2), (1, 3)])
def test_small_envmaps_match_mitsuba(tmp_path, h, w):
    from test_mitsuba_textures import real_mitsuba

    mi = real_mitsuba("Mitsuba 3 is not installed (pip install mitsuba==3.9.1): it checks the padding of small maps")
    import drjit as dr

    mi.set_variant("scalar_rgb")
    rng = np.random.default_rng(h * 10 + w)
    write_exr(tmp_path / "m.exr", (rng.random((h, w, 3)) * 3).astype(np.float32))
    ours = mitsuba("envmap", filename=("string", str(tmp_path / "m.exr")))
    theirs = mi.load_dict({"type": "envmap", "filename": str(tmp_path / "m.exr")})
    for d in unit(rng.normal(size=(100, 3))):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = mi.Vector3f(*(-d))
        np.testing.assert_allclose(ours.eval(d), np.array(theirs.eval(si)), rtol=1e-5, atol=1e-6)


def test_envmaps_from_8_and_16_bit_images_match_mitsuba(tmp_path):
    """An envmap reads any image a bitmap reads: 8- and 16-bit ones sRGB-decoded, 16-bit ones at float precision
    (Mitsuba's envmap converts to float32, where its bitmap texture keeps half floats)."""
    from PIL import Image
    from test_mitsuba_textures import real_mitsuba, write_png16

    mi = real_mitsuba("Mitsuba 3 is not installed (pip install mitsuba==3.9.1): it checks envmaps from 8/16-bit images")
    import drjit as dr

    mi.set_variant("scalar_rgb")
    rng = np.random.default_rng(31)
    Image.fromarray(rng.integers(0, 256, (6, 9, 3)).astype(np.uint8)).save(tmp_path / "sky.bmp")
    write_png16(tmp_path / "sky16.png", rng.integers(0, 65536, (6, 9, 3)).astype(np.uint16))
    for name in ("sky.bmp", "sky16.png"):
        ours = mitsuba("envmap", filename=("string", str(tmp_path / name)))
        theirs = mi.load_dict({"type": "envmap", "filename": str(tmp_path / name)})
        for d in unit(rng.normal(size=(100, 3))):
            si = dr.zeros(mi.SurfaceInteraction3f)
            si.wi = mi.Vector3f(*(-d))
            np.testing.assert_allclose(ours.eval(d), np.array(theirs.eval(si)), rtol=5e-5, atol=1e-7, err_msg=name)


def test_envmap_errors(tmp_path):
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
    on_sphere = np.zeros(film.image.shape[:2], bool)
    on_sphere[2:6, 2:6] = True             # the sphere covers the middle of the 8 x 8 image
    assert np.allclose(film.image[0, 0], L, rtol=1e-5), film.image[0, 0]      # background: exact
    res = compare_mean_to_value(film, 0.6 * L, 0.01, mask=on_sphere)
    assert res.passed, (res.message, film.image[on_sphere].mean())


# ------------------------------------------------------------------------------- selection in proportion to power
def test_power_selection_chi2_and_pdfs(tmp_path, ctx, queue, kernels, envmaps):
    env, _ = envmaps
    lights = [mitsuba("point", intensity=("color", 100.0), position=("point", [0.5, 2.0, 0.5])),
              mitsuba("spot", intensity=("color", [500.0, 900.0, 200.0]), to_world=("transform", Transform.lookat(
                  [1, 3, 1], [1, 0, 1], [0, 0, 1]))),
              mitsuba("directional", irradiance=("color", 3.0), direction=("vector", [0, -1, 0.2])),
              mitsuba("constant", radiance=("color", 0.2)),
              env]
    d = device(tmp_path, ctx, queue, kernels, lights, selection="power")
    radius = float(d.b.info["bounds_center"][0][3])
    prob = np.diff(np.concatenate([[0.0], selection_cdf([em.selection_power(radius, 0.0) for em in lights])]))
    assert prob.min() > 0.01 and prob.max() < 0.9 and np.ptp(prob) > 0.1      # far from uniform
    n = 200_000
    rng = np.random.default_rng(21)
    refs = np.concatenate([rng.uniform(0.2, 4.8, (n, 1)), np.full((n, 1), 0.01), rng.uniform(0.2, 4.8, (n, 1))], 1)
    s = d.sample(NONE, refs.astype(np.float32), rng.random((n, 3), dtype=np.float32))
    counts = np.bincount(s["emitter"], minlength=len(lights))
    res = stats.chisquare(counts, prob * n)
    assert res.pvalue > 1e-3, (counts, prob * n)
    em = s["emitter"]
    delta = np.isin(em, [0, 1, 2])
    # the pdfs carry the same selection probability: sampling, pdf(), and the environment's sum
    np.testing.assert_allclose(s["pdf"][delta], prob[em[delta]], rtol=1e-5)
    smooth = ~delta & (s["pdf"] > 0)
    np.testing.assert_allclose(s["pdf"][smooth], s["pdf_one"][smooth] * prob[em[smooth]], rtol=2e-4)
    np.testing.assert_allclose(s["pdf_again"][smooth], s["pdf"][smooth], rtol=2e-4)
    np.testing.assert_allclose(s["w"][smooth], s["eval"][smooth] / s["pdf"][smooth, None], rtol=2e-4, atol=1e-6)
    dirs = unit(rng.normal(size=(2000, 3))).astype(np.float32)
    envs = d.environment(dirs)
    one = Dev(d.ctx, d.queue, d.k, d.b)    # the same scene, each infinite light's own pdf
    pdf_c = 1 / (4 * np.pi)
    pdf_env = one.pdf_dirs(4, np.zeros(3), dirs)
    np.testing.assert_allclose(envs[:, 3], prob[3] * pdf_c + prob[4] * pdf_env, rtol=2e-4)
    # uniform selection stays what it was
    u = device(tmp_path, ctx, queue, kernels, lights, stem="u")
    su = u.sample(NONE, refs[:1000].astype(np.float32), rng.random((1000, 3), dtype=np.float32))
    dl = np.isin(su["emitter"], [0, 1, 2])
    np.testing.assert_allclose(su["pdf"][dl], 1 / len(lights))


def test_power_selection_keeps_mis_unbiased(tmp_path):
    """path_mis with a dim large ceiling light, an environment and a very bright small light that faces away
    (most of the power, none of the image): choosing lights by power must give the image of the uniform choice.
    The MIS weights of BSDF samples must use the same selection probabilities as light sampling (with 1/N there,
    the ceiling light's BSDF-sampled share is off by ~30 % here)."""
    write_exr(tmp_path / "sky.exr", sky_image())
    (tmp_path / "small.obj").write_text(tris_obj(quad([2.0, 3.0, 2.0], [0, 0, 0.1], [0.1, 0, 0])))   # faces up, above the ceiling
    (tmp_path / "big.obj").write_text(tris_obj(quad([-2, 2.5, -2], [4, 0, 0], [0, 0, 4])))            # faces down
    (tmp_path / "ground.obj").write_text(tris_obj(quad([-3, 0, -3], [0, 0, 6], [6, 0, 0])))
    xml = ('<scene><integrator type="path_mis"/><camera type="perspective"><float name="fov" value="60"/>'
           '<transform name="toWorld"><lookat origin="0, 2, 1.5" target="0, 0, 0" up="0, 1, 0"/></transform>'
           '<integer name="width" value="10"/><integer name="height" value="8"/></camera>'
           '<mesh type="obj"><string name="filename" value="ground.obj"/><bsdf type="diffuse"/></mesh>'
           '<mesh type="sphere"><point name="center" value="0, 0.5, 0"/><float name="radius" value="0.5"/></mesh>'
           '<mesh type="obj"><string name="filename" value="small.obj"/>'
           '<emitter type="area"><color name="radiance" value="30000"/></emitter></mesh>'
           '<mesh type="obj"><string name="filename" value="big.obj"/>'
           '<emitter type="area"><color name="radiance" value="1"/></emitter></mesh></scene>')
    (tmp_path / "s.xml").write_text(xml)
    films = []
    for sel, seed in (("uniform", 1), ("power", 2)):
        scene = clrender.load_scene(tmp_path / "s.xml")
        scene.emitters.append(mitsuba("envmap", filename=("string", str(tmp_path / "sky.exr")), scale=("float", 0.02)))
        scene.emitter_selection = sel
        films.append(clrender.render(scene, spp=256, seed=seed))
    res = compare_films(*films, alpha=0.01)
    assert res.passed, res.message
    assert films[0].image.mean() > 0.05


def test_cli_power_selection_is_for_mitsuba_scenes(tmp_path, capsys):
    from clrender.cli import main

    (tmp_path / "n.xml").write_text('<scene><integrator type="normals"/><camera type="perspective"><integer '
                                    'name="width" value="4"/><integer name="height" value="4"/></camera></scene>')
    assert main(["render", str(tmp_path / "n.xml"), "--emitter-selection", "power", "-q"]) == 2
    assert "is for Mitsuba scenes" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------- textured area light
LIGHT_OBJ = ("v -1 1 -1\nv 1 1 -1\nv 1 1 1\nv -1 1 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
             "f 1/1 2/2 3/3 4/4\n")   # faces down; uv = ((x + 1) / 2, (z + 1) / 2)


def textured_light_scene(tmp, integrator, to_uv=Transform.scale([2, 2, 1])):
    (tmp / "light.obj").write_text(LIGHT_OBJ)
    (tmp / "ground.obj").write_text(tris_obj(quad([0, 0, 0], [0, 0, 3], [3, 0, 0])))
    xml = (f'<scene><integrator type="{integrator}"/><camera type="perspective"><float name="fov" value="70"/>'
           '<transform name="toWorld"><lookat origin="0, 0.8, 2.5" target="0, 0, 0" up="0, 1, 0"/></transform>'
           '<integer name="width" value="8"/><integer name="height" value="6"/></camera>'
           '<mesh type="obj"><string name="filename" value="ground.obj"/><bsdf type="diffuse"/></mesh>'
           '<mesh type="obj"><string name="filename" value="light.obj"/>'
           '<emitter type="area"><color name="radiance" value="1"/></emitter></mesh></scene>')
    (tmp / "s.xml").write_text(xml)
    scene = load_scene(tmp / "s.xml")
    tex = registry.instantiate("texture", "checkerboard", {"color0": ("color", [4.0, 1.0, 0.5]),
                                                          "color1": ("color", [0.2, 0.5, 3.0]),
                                                          "to_uv": ("transform", to_uv)},
                               fmt="mitsuba")
    light = next(sh for sh in scene.shapes if sh.emitter is not None)
    light.emitter.texture = tex      # what a Mitsuba <emitter type="area"> with a nested radiance texture sets
    return scene, tex


def test_textured_area_light_eval_and_samples(tmp_path, ctx, queue, kernels):
    scene, tex = textured_light_scene(tmp_path, "normals")
    d = Dev(ctx, queue, kernels, pack_scene(scene))
    e = int(d.b.shapes[1]["emitter"])
    rng = np.random.default_rng(31)
    # camera-style rays from below hit the light where the texture is known
    targets = np.concatenate([rng.uniform(-0.99, 0.99, (500, 1)), np.full((500, 1), 1.0),
                              rng.uniform(-0.99, 0.99, (500, 1))], 1)
    org = np.array([0.1, 0.3, -0.2])
    out = d.hit_le(org, unit(targets - org).astype(np.float32))
    uv = np.stack([(targets[:, 0] + 1) / 2, (targets[:, 2] + 1) / 2], 1)
    st = 2 * uv
    frac = st - np.floor(st)
    clear = np.all(np.minimum(np.abs(frac - 0.5), np.minimum(frac, 1 - frac)) > 1e-3, axis=1)
    assert np.all(out[:, 3] == 1)
    np.testing.assert_allclose(out[clear, :3], tex.eval(uv[clear]), rtol=1e-6)
    # light samples: the radiance at the sampled point's uv, weight = eval / pdf
    refs = np.concatenate([rng.uniform(-1.5, 1.5, (2000, 1)), np.full((2000, 1), 0.01),
                           rng.uniform(-1.5, 1.5, (2000, 1))], 1).astype(np.float32)
    s = d.sample(e, refs, rng.random((2000, 2), dtype=np.float32))
    puv = np.stack([(s["p"][:, 0] + 1) / 2, (s["p"][:, 2] + 1) / 2], 1)
    frac = 2 * puv - np.floor(2 * puv)
    clear = np.all(np.minimum(np.abs(frac - 0.5), np.minimum(frac, 1 - frac)) > 1e-3, axis=1)
    np.testing.assert_allclose(s["eval"][clear], tex.eval(puv[clear]), rtol=1e-6)
    np.testing.assert_allclose(s["w"] * s["pdf"][:, None], s["eval"], rtol=2e-4, atol=1e-6)
    assert len(np.unique(s["eval"][:, 0])) == 2     # both colours seen


def test_textured_area_light_strategies_agree(tmp_path):
    """Light sampling (uv of the sampled point) and BSDF sampling (uv of the hit) see the same texture: here one
    colour on the half x < 0 of the light, the other on x > 0 (a wrong uv at sampled points moves the boundary)."""
    films = []
    for k, integrator in enumerate(("path_ems", "path_mats")):
        scene, _ = textured_light_scene(tmp_path, integrator, to_uv=Transform.scale([1, 0.5, 1]))
        films.append(clrender.render(scene, spp=512, seed=k + 1))
    res = compare_films(*films, alpha=0.01)
    assert res.passed, res.message


@pytest.mark.slow
@pytest.mark.parametrize("name", ["spot_point", "checkerboard"])
def test_power_selection_twins_match_mitsuba(name):
    """The twin scenes choosing lights in proportion to power converge to Mitsuba's image (which chooses
    uniformly): only the noise may change."""
    from pathlib import Path

    from clrender.testing.stats import compare_to_reference

    here = Path(__file__).resolve().parent / "mitsuba"
    with np.load(here / "refs" / f"{name}.npz") as z:
        mean, stderr, spp = z["mean"], z["stderr"], int(z["spp"])
    scene = clrender.load_scene(here / "scenes" / f"{name}.xml")
    scene.emitter_selection = "power"
    film = clrender.render(scene, seed=11)
    res = compare_to_reference(film, mean, stderr, ref_samples=spp)
    assert res.passed, res.message
