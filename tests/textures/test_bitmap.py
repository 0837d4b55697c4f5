"""Mitsuba 3's bitmap texture (clrender/textures/bitmap.py, kernels/textures/bitmap.h): its uv gradient, bumpmap's
slope, on the device and on the host against Mitsuba 3.9.1's eval_1_grad (tests/mitsuba/bsdf_values/perturbed.json,
written by make_perturbed_values.py there), a rendered plane that shows the image at its uv, its texel lookup on the
device against the host's for every filter and wrap mode (with and without sRGB decoding and a to_uv transform),
its pixels (sRGB, first row at t = 0, wrap modes), every image format it reads (against the formats'
specifications and Mitsuba 3.9.1), its `format` property, 16-bit images, and its errors (shared set-up:
image_common.py; its float view is tested in tests/test_mitsuba_textures.py)."""
import numpy as np
import pytest
from PIL import Image

from bsdfs.perturbed_common import DATA, spec
from clrender.errors import SceneError
from clrender.scene.registry import create
from clrender.scene.transform import Transform
from clrender.testing.plugin_checks import check_texture_render, texture_eval_batch
from clrender.textures.texture import TextureTable
from textures.image_common import bitmap, mitsuba_lookups, random_png, real_mitsuba, write_png16


@pytest.fixture(scope="module")
def png(tmp_path_factory):
    return random_png(tmp_path_factory.mktemp("tex"))


GRAD_SRC = r"""
#include "texture.h"
#include "textures/bitmap.h"
__kernel void grad(__global const Texture* textures, uint row, __global const float2* uv, __global float2* out) {
    uint i = get_global_id(0);
    out[i] = bitmap_grad(textures + row, uv[i]);
}
"""


@pytest.mark.plugin("bitmap", "eval")
@pytest.mark.parametrize("name", sorted(DATA["gradients"]))
def test_bitmap_gradient_is_mitsubas(ctx, queue, name):
    """bumpmap's slope: the bitmap's uv gradient on the device (bitmap_grad) and on the host (Bitmap.eval_grad) as
    Mitsuba's eval_1_grad gives it (of the luminance, through to_uv, every wrap mode; none for `nearest`)."""
    import pyopencl as cl

    from clrender.device.program import build_program

    case = DATA["gradients"][name]
    tex = create(spec(case["dict"], "texture")).float_view()
    uv, ref = np.array(case["uv"]), np.array(case["grad"])
    np.testing.assert_allclose(tex.eval_grad(uv), ref, rtol=1e-4, atol=1e-4 * np.abs(ref).max())
    table = TextureTable()
    row = table.add(tex)
    mf = cl.mem_flags
    d_tex = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=table.array())
    d_uv = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=uv.astype(np.float32))
    out = np.empty((len(uv), 2), np.float32)
    d_out = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
    cl.Kernel(build_program(ctx, GRAD_SRC), "grad")(queue, (len(uv),), None, d_tex, np.uint32(row), d_uv, d_out)
    cl.enqueue_copy(queue, out, d_out)
    queue.finish()
    np.testing.assert_allclose(out, ref, rtol=1e-3, atol=1e-3 * np.abs(ref).max())
    if name == "nearest":
        assert not ref.any()
    else:
        assert np.abs(ref).max() > 0.5


@pytest.mark.plugin("bitmap", "render")
def test_furnace_render(tmp_path, png):
    """A diffuse plane with a bitmap reflectance (a 5 x 7 sRGB PNG, bilinear) in a constant environment of radiance 1
    shows the image's value at its uv."""
    check_texture_render(tmp_path, f'<texture type="bitmap" name="reflectance"><string name="filename" '
                                   f'value="{png[0]}"/></texture>', "mitsuba")


# ---------------------------------------------------------------------------------------------------- lookups
TO_UV = Transform.translate([0.25, 0.1, 0.3]) @ Transform.scale([2, 3, 1]) @ Transform.rotate([0, 0, 1], 30)


@pytest.mark.parametrize("filt", ["bilinear", "nearest"])
@pytest.mark.parametrize("wrap", ["repeat", "mirror", "clamp"])
def test_bitmap_lookup_matches_host(ctx, queue, png, filt, wrap):
    path, _ = png
    texs = [bitmap(path, filter_type=filt, wrap_mode=wrap), bitmap(path, filter_type=filt, wrap_mode=wrap, raw=True),
            bitmap(path, filter_type=filt, wrap_mode=wrap, to_uv=TO_UV)]
    uv = np.random.default_rng(5).uniform(-2.5, 3.5, size=(3000, 2))
    # also exact texel centres and edges, where nearest and bilinear switch
    g = np.stack(np.meshgrid(np.arange(-7, 15) / 7.0, np.arange(-5, 11) / 5.0), -1).reshape(-1, 2) + 1e-4
    uv = np.concatenate([uv, g])
    for t, dev in zip(texs, texture_eval_batch(ctx, queue, texs, uv)):
        # float32 st on the device: positions differ by ~1e-6 pixel, values by that times a pixel step
        np.testing.assert_allclose(dev, t.eval(uv.astype(np.float32)), rtol=1e-5, atol=5e-5)


def test_bitmap_pixels_and_srgb(png):
    path, img = png
    raw, lin = bitmap(path, raw=True), bitmap(path, filter_type="nearest")
    np.testing.assert_allclose(raw.image, img / 255.0, atol=1e-7)
    # sRGB decoding, spot values of IEC 61966-2-1: 0.5 -> 0.21404, 0.04 -> 0.04/12.92, 1 -> 1
    for code, linear in ((0, 0.0), (10, 10 / 255 / 12.92), (128, ((128 / 255 + 0.055) / 1.055) ** 2.4), (255, 1.0)):
        sel = img == code
        if sel.any():
            np.testing.assert_allclose(lin.image[sel], linear, rtol=1e-6)
    assert lin.image.min() >= 0 and lin.image.max() <= 1
    assert abs(((128 / 255 + 0.055) / 1.055) ** 2.4 - 0.2158605) < 1e-6
    # the first image row is at t = 0, the first column at s = 0 (no flip)
    np.testing.assert_allclose(raw.eval([[0.5 / 7, 0.5 / 5], [6.5 / 7, 0.5 / 5], [0.5 / 7, 4.5 / 5]]),
                               img[[0, 0, 4], [0, 6, 0]] / 255.0, atol=1e-6)
    # wrap modes at a known pixel: one texel left of column 0
    for mode, col in (("repeat", 6), ("mirror", 0), ("clamp", 0)):
        t = bitmap(path, filter_type="nearest", wrap_mode=mode, raw=True)
        np.testing.assert_allclose(t.eval([-0.5 / 7, 0.5 / 5]), img[0, col] / 255.0, atol=1e-6)
    t = bitmap(path, filter_type="nearest", wrap_mode="mirror", raw=True)
    np.testing.assert_allclose(t.eval([-1.5 / 7, 0.5 / 5]), img[0, 1] / 255.0, atol=1e-6)


def test_texture_errors(tmp_path, png):
    path, _ = png
    with pytest.raises(SceneError, match="wrap_mode must be one of repeat, mirror, clamp"):
        bitmap(path, wrap_mode="border")
    with pytest.raises(SceneError, match="filter_type must be one of bilinear, nearest"):
        bitmap(path, filter_type="trilinear")
    with pytest.raises(SceneError, match="not found"):
        bitmap(tmp_path / "nope.png")
    (tmp_path / "x.tga").write_bytes(b"\0" * 20)
    with pytest.raises(SceneError, match="unsupported image format"):
        bitmap(tmp_path / "x.tga")
    (tmp_path / "bad.png").write_bytes(b"not a png")
    with pytest.raises(SceneError, match="cannot read image"):
        bitmap(tmp_path / "bad.png")


# ---------------------------------------------------------------------------------------------------- 16-bit PNGs
def test_16_bit_pngs_keep_their_precision(tmp_path):
    """A 16-bit PNG is read at 16 bits (Pillow alone gives 8: a colour one lost its low bytes, a grey one was an
    error), sRGB-decoded unless raw, and kept as half floats as Mitsuba 3.9.1 keeps it."""
    from clrender.textures.imagefile import read_image, srgb_to_linear

    img = np.random.default_rng(11).integers(0, 65536, size=(7, 5, 3)).astype(np.uint16)
    img[0, 0] = [0x1234, 0x00ff, 0xff01]         # low bytes that 8 bits would lose
    write_png16(tmp_path / "c.png", img)
    v = img / 65535.0
    np.testing.assert_array_equal(read_image(tmp_path / "c.png", raw=True), v.astype(np.float16).astype(np.float32))
    np.testing.assert_array_equal(read_image(tmp_path / "c.png"), srgb_to_linear(v).astype(np.float16).astype(np.float32))
    Image.fromarray(img[..., 0]).save(tmp_path / "g.png")      # Pillow writes mode I;16 as 16-bit grey
    np.testing.assert_array_equal(read_image(tmp_path / "g.png", raw=True),
                                  np.repeat(v[..., :1], 3, -1).astype(np.float16).astype(np.float32))


def test_16_bit_pngs_match_mitsuba(tmp_path):
    mi = real_mitsuba("Mitsuba 3 is not installed (pip install mitsuba==3.9.1): it checks 16-bit PNG textures")
    mi.set_variant("scalar_rgb")
    rng = np.random.default_rng(12)
    mi.Bitmap(rng.integers(0, 65536, size=(5, 7, 3)).astype(np.uint16), mi.Bitmap.PixelFormat.RGB).write(
        str(tmp_path / "rgb.png"))
    mi.Bitmap(rng.integers(0, 65536, size=(5, 7, 4)).astype(np.uint16), mi.Bitmap.PixelFormat.RGBA).write(
        str(tmp_path / "rgba.png"))
    uv = rng.uniform(0.01, 0.99, size=(100, 2))
    for name in ("rgb.png", "rgba.png"):
        for raw in (False, True):
            want = mitsuba_lookups(mi, {"type": "bitmap", "filename": str(tmp_path / name), "raw": raw}, uv)
            np.testing.assert_allclose(bitmap(tmp_path / name, raw=raw).eval(uv), want, atol=1e-6,
                                       err_msg=f"{name} raw={raw}")


def format_images(tmp_path):
    """A float EXR (values around byte and half steps, below 0 and above 1) and a 16-bit PNG."""
    import OpenEXR

    rng = np.random.default_rng(21)
    f = rng.uniform(-0.2, 1.3, size=(6, 5, 3)).astype(np.float32)
    f[0, :3, 0] = [0.002, 0.0025, 0.70001]
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                 {"RGB": f}).write(str(tmp_path / "f.exr"))
    p = rng.integers(0, 65536, size=(6, 5, 3)).astype(np.uint16)
    write_png16(tmp_path / "p.png", p)
    return f, p


@pytest.mark.parametrize("raw", [False, True])
def test_bitmap_format_sets_the_texels_precision(tmp_path, raw):
    """Mitsuba 3.9.1's bitmap `format`: variant keeps float32 (a 16-bit image unrounded), float16 rounds every value
    to half, uint8 every channel to a byte (a 16-bit image's encoded values, decoded after; a float image's
    clamped to [0, 1]); auto is the default's half-rounded 16 bits. Values derived from each definition."""
    from clrender.textures.imagefile import srgb_to_linear

    f, p = format_images(tmp_path)
    decode = (lambda x: x) if raw else srgb_to_linear
    v = p / 65535.0
    half = lambda x: np.asarray(x, np.float32).astype(np.float16).astype(np.float32)   # noqa: E731
    byte = lambda x: np.round(np.clip(x, 0, 1) * 255) / 255                             # noqa: E731
    want = {("f.exr", "auto"): f, ("f.exr", "variant"): f, ("f.exr", "float16"): half(f),
            ("f.exr", "fp16"): half(f), ("f.exr", "uint8"): byte(f),
            ("p.png", "auto"): half(decode(v)), ("p.png", "variant"): decode(v),
            ("p.png", "float16"): half(decode(v)), ("p.png", "uint8"): decode(byte(v))}
    for (name, fmt), expect in want.items():
        got = bitmap(tmp_path / name, raw=raw, format=fmt).image
        np.testing.assert_allclose(got, np.asarray(expect, np.float32), rtol=0, atol=1e-7, err_msg=f"{name} {fmt}")
    with pytest.raises(SceneError, match="format must be one of auto, variant, float16, uint8"):
        bitmap(tmp_path / "p.png", format="half")


def test_bitmap_format_matches_mitsuba(tmp_path):
    """The same lookups by Mitsuba 3.9.1 itself: equal for auto, variant and float16; for uint8 within one byte step
    (Mitsuba dithers when it turns 16-bit or float values into bytes)."""
    mi = real_mitsuba("Mitsuba 3 is not installed (pip install mitsuba==3.9.1): it checks bitmap formats")
    mi.set_variant("scalar_rgb")
    format_images(tmp_path)
    uv = (np.stack(np.meshgrid(np.arange(5), np.arange(6)), -1).reshape(-1, 2) + 0.5) / [5, 6]
    for name in ("f.exr", "p.png"):
        for fmt in ("auto", "variant", "float16", "uint8"):
            want = mitsuba_lookups(mi, {"type": "bitmap", "filename": str(tmp_path / name), "format": fmt,
                                        "filter_type": "nearest"}, uv)
            ours = bitmap(tmp_path / name, format=fmt, filter_type="nearest").eval(uv)
            if fmt == "uint8":   # one byte step: 1/255 of a linear value, at most 0.009 once an encoded one is decoded
                np.testing.assert_allclose(ours, want, rtol=0, atol=1 / 255 + 1e-6 if name == "f.exr" else 0.009)
            else:
                np.testing.assert_allclose(ours, want, rtol=0, atol=1e-6, err_msg=f"{name} {fmt}")   # float32 decoding


def test_16_bit_grey_png_is_read(tmp_path):
    # It used to be refused ("only 8-bit ... images"); Mitsuba reads it, sRGB-decoded unless raw like 8-bit ones,
    # and keeps the values as half floats (hence the tolerance).
    from PIL import Image

    from clrender.textures.imagefile import read_image, srgb_to_linear

    values = (np.arange(12).reshape(3, 4) * 5000).astype(np.uint16)
    Image.fromarray(values).save(tmp_path / "g.png")
    raw = read_image(tmp_path / "g.png", raw=True)
    assert raw.shape == (3, 4, 3)
    np.testing.assert_allclose(raw[..., 1], values / 65535.0, rtol=1e-3)
    np.testing.assert_allclose(read_image(tmp_path / "g.png")[..., 0], srgb_to_linear(values / 65535.0), rtol=1e-3)


# ---------------------------------------------------------------------------------------------------- image formats
def write_tiff16(path, img, order="<"):
    """An uncompressed 16-bit RGB TIFF with the baseline tags only, byte order '<' (II) or '>' (MM)."""
    import struct

    h, w, _ = img.shape
    data = img.astype(order + "u2").tobytes()
    tags = [(256, 3, w), (257, 3, h), (258, 3, None), (259, 3, 1), (262, 3, 2), (273, 4, None), (277, 3, 3),
            (278, 3, h), (279, 4, len(data)), (284, 3, 1)]
    extra_at = 8 + 2 + 12 * len(tags) + 4       # BitsPerSample's three values follow the directory
    data_at = extra_at + 6
    out = (b"II*\0" if order == "<" else b"MM\0*") + struct.pack(order + "IH", 8, len(tags))
    for tag, kind, value in tags:
        n = 3 if tag == 258 else 1
        value = extra_at if tag == 258 else data_at if tag == 273 else value
        out += struct.pack(order + "HHI", tag, kind, n)
        out += struct.pack(order + ("HH" if kind == 3 and n == 1 else "I"), *((value, 0) if kind == 3 and n == 1
                                                                               else (value,)))
    path.write_bytes(out + struct.pack(order + "I", 0) + struct.pack(order + "HHH", 16, 16, 16) + data)


def write_pfm(path, img, scale=1.0, little=True):
    """A PFM (colour 'PF' or grey 'Pf'): rows bottom-up, the scale's sign giving the byte order."""
    h, w = img.shape[:2]
    magic = b"PF" if img.ndim == 3 else b"Pf"
    head = magic + f"\n{w} {h}\n{-scale if little else scale}\n".encode()
    path.write_bytes(head + np.ascontiguousarray(img[::-1], "<f4" if little else ">f4").tobytes())


@pytest.fixture(scope="module")
def image_files(tmp_path_factory):
    """The same pixels in every format we read (written by Pillow or by hand after the formats' specifications), with
    the linear values each must give: (file, expected with raw=False, expected with raw=True)."""
    from clrender.textures.imagefile import srgb_to_linear

    d = tmp_path_factory.mktemp("formats")
    rng = np.random.default_rng(21)
    c8 = rng.integers(0, 256, (5, 7, 4)).astype(np.uint8)
    c16 = rng.integers(0, 65536, (5, 7, 3)).astype(np.uint16)
    f32 = (rng.random((5, 7, 3)) * 4).astype(np.float32)
    rgb, grey = c8[..., :3] / 255.0, np.repeat(c8[..., :1] / 255.0, 3, -1)
    eight = lambda v: (srgb_to_linear(v).astype(np.float32), v.astype(np.float32))   # noqa: E731
    half = lambda v: (srgb_to_linear(v).astype(np.float16).astype(np.float32),       # noqa: E731
                      v.astype(np.float16).astype(np.float32))
    linear = lambda v: (v.astype(np.float32), v.astype(np.float32))                 # noqa: E731
    cases = {}
    for name, arr, mode, kw in (("rgb.bmp", c8[..., :3], None, {}), ("rgba.bmp", c8, None, {}),
                                ("grey.bmp", c8[..., 0], None, {}), ("rgb.tga", c8[..., :3], None, {}),
                                ("rgba.tga", c8, None, {}), ("grey.tga", c8[..., 0], None, {}),
                                ("rle.tga", c8[..., :3], None, {"compression": "tga_rle"}),
                                ("rgb.ppm", c8[..., :3], None, {}), ("grey.pgm", c8[..., 0], None, {}),
                                ("lzw.tif", c8[..., :3], None, {"compression": "tiff_lzw"}),
                                ("rgba.tif", c8, None, {}), ("greya.png", c8[..., :2], "LA", {})):
        Image.fromarray(arr, mode).save(d / name, **kw)
        cases[name] = eight(grey if arr.ndim == 2 or mode == "LA" else rgb)
    Image.fromarray(c16[..., 0]).save(d / "grey16.tif")      # Pillow writes mode I;16 as 16-bit grey
    cases["grey16.tif"] = half(np.repeat(c16[..., :1] / 65535.0, 3, -1))
    (d / "grey16.pgm").write_bytes(b"P5\n7 5\n65535\n" + c16[..., 0].astype(">u2").tobytes())
    cases["grey16.pgm"] = cases["grey16.tif"]
    (d / "rgb16.ppm").write_bytes(b"P6\n# a comment\n7 5\n65535\n" + c16.astype(">u2").tobytes())   # big-endian
    for order in "<>":
        write_tiff16(d / f"rgb16{order == '<' and 'le' or 'be'}.tif", c16, order)
    for name in ("rgb16.ppm", "rgb16le.tif", "rgb16be.tif"):
        cases[name] = half(c16 / 65535.0)
    write_pfm(d / "le.pfm", f32, scale=1.0)
    write_pfm(d / "be2.pfm", f32 / 2, scale=2.0, little=False)       # Mitsuba multiplies by the scale
    write_pfm(d / "grey.pfm", f32[..., 0] / 4, scale=4.0)
    cases["le.pfm"] = cases["be2.pfm"] = linear(f32)
    cases["grey.pfm"] = linear(np.repeat(f32[..., :1], 3, -1))
    Image.fromarray(c8[..., :3]).save(d / "really-a-png.jpg", format="PNG")   # read by content, as Mitsuba does
    cases["really-a-png.jpg"] = cases["rgb.bmp"]
    return [(d / name, *values) for name, values in cases.items()]


def test_image_formats(image_files):
    """BMP, TGA (plain and run-length), PPM/PGM (8 and 16 bits), TIFF (8 bits, LZW; 16-bit grey and colour in
    both byte orders), PFM (colour and grey, both byte orders, with a scale), alpha dropped: every pixel, sRGB-decoded
    unless raw; 16-bit values at half precision as Mitsuba keeps them; first row at t = 0."""
    from clrender.textures.imagefile import read_image

    for path, want, want_raw in image_files:
        np.testing.assert_allclose(read_image(path), want, rtol=1e-6, atol=1e-7, err_msg=path.name)
        np.testing.assert_allclose(read_image(path, raw=True), want_raw, rtol=1e-6, atol=1e-7, err_msg=path.name)
        t = bitmap(path, filter_type="nearest")
        np.testing.assert_allclose(t.eval([[0.5 / 7, 0.5 / 5], [6.5 / 7, 4.5 / 5]]), want[[0, 4], [0, 6]],
                                   rtol=1e-6, atol=1e-7, err_msg=path.name)


def test_image_formats_match_mitsuba(image_files):
    """Mitsuba 3.9.1's own bitmap texture reads the same values from the formats it reads (it reads no TIFF, no
    greyscale PPM; its 16-bit PPM is little-endian, against the Netpbm specification that we and Pillow follow)."""
    mi = real_mitsuba("Mitsuba 3 is not installed (pip install mitsuba==3.9.1): it checks the image formats")
    mi.set_variant("scalar_rgb")
    uv = np.stack(np.meshgrid((np.arange(7) + 0.5) / 7, (np.arange(5) + 0.5) / 5), -1).reshape(-1, 2)
    checked = 0
    for path, _, _ in image_files:
        if path.suffix in (".tif", ".pgm") or path.name == "rgb16.ppm":
            continue
        for raw in (False, True):
            want = mitsuba_lookups(mi, {"type": "bitmap", "filename": str(path), "raw": raw, "filter_type": "nearest"},
                                   uv)
            np.testing.assert_allclose(bitmap(path, raw=raw, filter_type="nearest").eval(uv), want, rtol=1e-6,
                                       atol=1e-7, err_msg=f"{path.name} raw={raw}")
            checked += 1
    assert checked == 2 * 13
    from clrender.textures.imagefile import read_image

    f32 = (np.random.default_rng(22).random((5, 20, 3)) * 40).astype(np.float32)   # >= 8 wide: RLE rows
    for name in ("mi.hdr", "mi.pfm"):   # as Mitsuba writes them (its RGBE is run-length encoded)
        path = image_files[0][0].parent / name
        mi.Bitmap(f32).write(str(path))
        np.testing.assert_array_equal(read_image(path), np.array(mi.Bitmap(str(path))), err_msg=name)


def test_unsupported_images(tmp_path):
    Image.fromarray(np.zeros((2, 2), np.uint8)).save(tmp_path / "a.gif")
    with pytest.raises(SceneError, match=r"unsupported image format \(its content is none of OpenEXR"):
        bitmap(tmp_path / "a.gif")
    (tmp_path / "lfs.exr").write_bytes(b"version https://git-lfs.github.com/spec/v1\noid sha256:0\nsize 9\n")
    with pytest.raises(SceneError, match=r"none of OpenEXR.*\); this is a Git LFS pointer, not the file"):
        bitmap(tmp_path / "lfs.exr")
    (tmp_path / "short.pfm").write_bytes(b"PF\n4 4\n-1\n" + bytes(20))
    with pytest.raises(SceneError, match="ends before its 4 x 4 pixels"):
        bitmap(tmp_path / "short.pfm")
    (tmp_path / "short.ppm").write_bytes(b"P6\n4 4\n65535\n" + bytes(20))
    with pytest.raises(SceneError, match="ends before its 48 samples"):
        bitmap(tmp_path / "short.ppm")
