"""Mitsuba 3's envmap (clrender/emitters/envmap.py, kernels/emitters/envmap.h) on the device: its RGBE and EXR
maps read, the lat-long lookup against a numpy reference and Mitsuba's orientation, chi-square of the 2-D importance
sampling against its pdf, weight = eval / pdf and the pdf normalised over the sphere, small maps padded as Mitsuba
pads them, its errors, and a furnace through path_mis (a constant map around a diffuse sphere: a L on the sphere,
L elsewhere) in which pdf and eval must agree for MIS to stay unbiased. (Set-up: emitter_common.py.)"""
import numpy as np
import pytest

import clrender
from clrender.errors import SceneError
from clrender.scene.transform import Transform
from clrender.testing.stats import compare_mean_to_value
from clrender.textures.imagefile import read_image, write_rgbe

from .emitter_common import device, mitsuba, run_chi2, sky_image, unit, write_exr


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


@pytest.mark.plugin("envmap", "sampling")
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


def test_a_lone_bright_texel_is_sampled_as_it_shines(tmp_path, ctx, queue, kernels):
    """Within a cell, directions are drawn in proportion to the bilinear patch of its corners (as Mitsuba's envmap
    warp draws them): for a map of one bright texel near the horizon, the sample weights radiance / pdf then vary
    only with sin(theta) across its four cells (a few per cent), where drawing uniformly in a cell gave weights
    4 (1 - x)(1 - y) / p, a relative spread of 0.88. Chi-square of these samples: test_envmap_chi2 and below."""
    img = np.zeros((9, 16, 3), np.float32)
    img[4, 6] = [3.0, 2.0, 1.0]
    write_exr(tmp_path / "texel.exr", img)
    em = mitsuba("envmap", filename=("string", str(tmp_path / "texel.exr")))
    d = device(tmp_path, ctx, queue, kernels, [em], stem="texel")
    s = d.sample(0, np.zeros(3), np.random.default_rng(11).random((20_000, 2), dtype=np.float32))
    w = s["w"][s["pdf"] > 0] @ np.array([0.212671, 0.715160, 0.072169])
    assert len(w) > 19_000 and w.std() / w.mean() < 0.05, (len(w), w.std() / w.mean())
    r = run_chi2(d, 0, np.zeros(3), 0, 200_000, 16, seed=79, n_tests=1)
    assert r.passed, r.message


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
    from textures.image_common import real_mitsuba

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
    from textures.image_common import real_mitsuba, write_png16

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


@pytest.mark.plugin("envmap", "render")
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
    # filter sampling: a corner pixel's footprint then holds background alone (a splatting film's also takes the
    # samples of pixel (2, 2), which reach the sphere)
    film = clrender.render(scene, spp=512, seed=3, reconstruction="sampling")
    L = 1.6
    on_sphere = np.zeros(film.image.shape[:2], bool)
    on_sphere[2:6, 2:6] = True             # the sphere covers the middle of the 8 x 8 image
    assert np.allclose(film.image[0, 0], L, rtol=1e-5), film.image[0, 0]      # background: exact
    res = compare_mean_to_value(film, 0.6 * L, 0.01, mask=on_sphere)
    assert res.passed, (res.message, film.image[on_sphere].mean())
