"""Mitsuba 3 textures (clrender/textures/bitmap.py, checkerboard.py) evaluated by the kernels against their host
references (numpy), which were checked against Mitsuba 3.9.1's own plugins (see their docstrings): bitmap texel
lookup for every filter and wrap mode, with and without sRGB decoding and a to_uv transform; the checkerboard
pattern; known sRGB values; errors."""
import numpy as np
import pytest
from PIL import Image

from clrender import plugins  # noqa: F401  (registers the plugins)
from clrender.errors import SceneError
from clrender.scene import registry
from clrender.scene.transform import Transform
from clrender.testing.plugin_checks import texture_eval_batch


def bitmap(path, **props):
    p = {"filename": ("string", str(path))}
    for k, v in props.items():
        p[k] = ("boolean", v) if isinstance(v, bool) else ("transform", v) if isinstance(v, Transform) else ("string", v)
    return registry.instantiate("texture", "bitmap", p, fmt="mitsuba")


@pytest.fixture(scope="module")
def png(tmp_path_factory):
    d = tmp_path_factory.mktemp("tex")
    img = (np.random.default_rng(4).random((5, 7, 3)) * 255).astype(np.uint8)
    Image.fromarray(img).save(d / "t.png")
    return d / "t.png", img


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


def real_mitsuba(reason):
    """Mitsuba 3 itself, or a skip. Without it, `import mitsuba` finds tests/mitsuba/ (our reference data) as a
    namespace package of that name, so pytest.importorskip would not skip."""
    import sys

    try:
        import mitsuba as mi
    except ImportError:
        mi = None
    if mi is None or not hasattr(mi, "set_variant"):
        sys.modules.pop("mitsuba", None)
        pytest.skip(reason)
    return mi


# ------------------------------------------------------------------------- a texture where a float parameter takes it
LUM = np.array([0.212671, 0.715160, 0.072169])


def checkerboard(c0, c1, to_uv=None):
    p = {"color0": ("color", c0), "color1": ("color", c1)}
    if to_uv is not None:
        p["to_uv"] = ("transform", to_uv)
    return registry.instantiate("texture", "checkerboard", p, fmt="mitsuba")


def test_float_view_is_mitsubas_float_lookup(png):
    """A roughness, blend weight or opacity texture is read as Mitsuba's eval_1 reads it: a bitmap's luminance
    (not its red channel), and for a checkerboard the channel mean of the *other* cell's colour (Mitsuba 3.9.1's
    float lookup tests the cells the other way round from its colour lookup)."""
    path, img = png
    t = bitmap(path, raw=True, filter_type="nearest")
    v = t.float_view()
    assert v is t.float_view() and v.float_view() is v          # one object, so the table holds it once
    np.testing.assert_allclose(v.image, np.repeat((img / 255.0 @ LUM)[..., None], 3, -1), rtol=1e-6)
    np.testing.assert_allclose(t.image, img / 255.0, atol=1e-7)   # the colour lookup is unchanged
    c = checkerboard([0.9, 0.1, 0.2], [0.05, 0.3, 0.7])
    np.testing.assert_allclose(c.float_view().eval([[0.2, 0.2], [0.7, 0.2]]), [[0.35] * 3, [0.4] * 3])
    np.testing.assert_allclose(c.eval([[0.2, 0.2]]), [[0.9, 0.1, 0.2]])


def test_float_view_on_the_device(ctx, queue, png):
    path, _ = png
    t, c = bitmap(path), checkerboard([0.9, 0.1, 0.2], [0.05, 0.3, 0.7], Transform.scale([3, 2, 1]))
    uv = np.random.default_rng(8).uniform(-1, 2, size=(500, 2))
    views = [t.float_view(), c.float_view()]
    for v, dev in zip(views, texture_eval_batch(ctx, queue, views, uv)):
        np.testing.assert_allclose(dev, v.eval(uv.astype(np.float32)), rtol=1e-5, atol=5e-5)


def test_float_view_matches_mitsuba(tmp_path, png):
    """Against Mitsuba 3's own eval_1 at random uvs (PNG sRGB and raw, EXR, a checkerboard with to_uv)."""
    mi = real_mitsuba("Mitsuba 3 is not installed (pip install mitsuba==3.9.1): it checks the float lookup")
    mi.set_variant("scalar_rgb")
    path, _ = png
    exr = np.random.default_rng(9).uniform(0, 3, size=(4, 6, 3)).astype(np.float32)
    mi.Bitmap(exr).write(str(tmp_path / "t.exr"))
    cases = [(bitmap(path), {"type": "bitmap", "filename": str(path)}),
             (bitmap(path, raw=True), {"type": "bitmap", "filename": str(path), "raw": True}),
             (bitmap(tmp_path / "t.exr"), {"type": "bitmap", "filename": str(tmp_path / "t.exr")}),
             (checkerboard([0.9, 0.1, 0.2], [0.05, 0.3, 0.7], Transform.scale([3, 2, 1])),
              {"type": "checkerboard", "color0": {"type": "rgb", "value": [0.9, 0.1, 0.2]},
               "color1": {"type": "rgb", "value": [0.05, 0.3, 0.7]}, "to_uv": mi.ScalarTransform4f().scale([3, 2, 1])})]
    uv = np.random.default_rng(10).uniform(0.01, 0.99, size=(200, 2))
    for ours, d in cases:
        theirs = mi.load_dict(d)
        si = mi.SurfaceInteraction3f()
        want = []
        for u in uv:
            si.uv = mi.Point2f(*u)
            want.append(theirs.eval_1(si))
        np.testing.assert_allclose(ours.float_view().eval(uv)[:, 0], want, rtol=2e-5, atol=1e-6, err_msg=d["type"])


FURNACE = """<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="30"/>
        <film type="hdrfilm"><integer name="width" value="6"/><integer name="height" value="6"/>
            <rfilter type="box"/></film></sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="10"/><rotate y="1" angle="180"/><translate z="2"/></transform>
        {bsdf}
    </shape>
</scene>"""
BLACK, WHITE = ('<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>',
                '<bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf>')


@pytest.mark.parametrize("bsdf, expect", [
    # blend of black and white under a unit sky: the weight; a mask over black: 1 - opacity
    (f'<bsdf type="blendbsdf">{{tex}}{BLACK}{WHITE}</bsdf>', lambda w: w),
    (f'<bsdf type="mask">{{tex}}{BLACK}</bsdf>', lambda w: 1 - w),
], ids=["blendbsdf weight", "mask opacity"])
@pytest.mark.parametrize("given", ["float", "bitmap", "rgb", "rawconstant"])
def test_float_parameter_in_a_furnace(tmp_path, bsdf, expect, given):
    """A coloured texture (or colour) where a float is read renders as Mitsuba reads it: the bitmap's luminance, the
    colour's channel mean (a red-channel reading gives 0.9 or 0.1 here). The blend's black child reflects nothing,
    but the directions it samples are samples of the mixture (they were once dropped: 0.2 for 0.4)."""
    import clrender
    from clrender.testing.stats import compare_mean_to_value

    rgb = np.array([230, 51, 26], np.uint8)
    name = "weight" if "blend" in bsdf else "opacity"
    if given == "float":
        tex, w = f'<float name="{name}" value="0.4"/>', 0.4
    elif given == "bitmap":
        Image.fromarray(np.tile(rgb, (2, 2, 1))).save(tmp_path / "c.png")
        tex = (f'<texture type="bitmap" name="{name}"><string name="filename" value="c.png"/>'
               f'<boolean name="raw" value="true"/></texture>')
        w = float(rgb / 255.0 @ LUM)
    elif given == "rawconstant":
        tex, w = f'<texture type="rawconstant" name="{name}"><float name="value" value="0.4"/></texture>', 0.4
    else:
        tex = f'<rgb name="{name}" value="{", ".join(str(c / 255) for c in rgb)}"/>'
        w = float((rgb / 255.0).mean())
    (tmp_path / "s.xml").write_text(FURNACE.format(bsdf=bsdf.format(tex=tex)))
    film = clrender.render(clrender.load_scene(tmp_path / "s.xml"), spp=64, seed=2)
    res = compare_mean_to_value(film, expect(w))
    assert res.passed, (res.message, film.image.mean(axis=(0, 1)), expect(w))


def test_blend_of_a_mirror_and_diffuse_in_a_furnace(tmp_path):
    """blendbsdf of a perfect mirror and a diffuse 0.8 at weight 0.5 under a unit sky: exactly 0.5 + 0.5 x 0.8.
    Mitsuba 3.9.1 renders 0.875 here (its blend adds the diffuse child's density to the mirror's discrete
    probability when the mirror is sampled, which darkens the mirror's share; README, known differences)."""
    import clrender
    from clrender.testing.stats import compare_mean_to_value

    bsdf = ('<bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="conductor"/>'
            '<bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf></bsdf>')
    (tmp_path / "s.xml").write_text(FURNACE.format(bsdf=bsdf))
    film = clrender.render(clrender.load_scene(tmp_path / "s.xml"), spp=256, seed=4)
    res = compare_mean_to_value(film, 0.9)
    assert res.passed, (res.message, film.image.mean(axis=(0, 1)))


# ---------------------------------------------------------------------------------------------------- 16-bit PNGs
def write_png16(path, img):
    """A 16-bit RGB PNG (colour type 2, depth 16), its rows filtered None, Sub and Up in turn."""
    import struct
    import zlib

    h, w, _ = img.shape
    data = img.astype(">u2").tobytes()
    stride, rows = w * 6, []
    prev = bytes(stride)
    for y in range(h):
        row = np.frombuffer(data[y * stride:(y + 1) * stride], np.uint8).astype(np.int32)
        kind = y % 3
        if kind == 1:   # Sub: minus the byte one pixel (6 bytes) to the left
            out = row - np.concatenate([np.zeros(6, np.int32), row[:-6]])
        elif kind == 2:   # Up: minus the byte above
            out = row - np.frombuffer(prev, np.uint8).astype(np.int32)
        else:
            out = row
        rows.append(bytes([kind]) + (out % 256).astype(np.uint8).tobytes())
        prev = row.astype(np.uint8).tobytes()

    def chunk(kind, payload):
        return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload))

    ihdr = struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"".join(rows)))
                     + chunk(b"IEND", b""))


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
    si = mi.SurfaceInteraction3f()
    for name in ("rgb.png", "rgba.png"):
        for raw in (False, True):
            theirs = mi.load_dict({"type": "bitmap", "filename": str(tmp_path / name), "raw": raw})
            want = []
            for u in uv:
                si.uv = mi.Point2f(*u)
                want.append(np.array(theirs.eval(si)))
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
    si = mi.SurfaceInteraction3f()
    uv = (np.stack(np.meshgrid(np.arange(5), np.arange(6)), -1).reshape(-1, 2) + 0.5) / [5, 6]
    for name in ("f.exr", "p.png"):
        for fmt in ("auto", "variant", "float16", "uint8"):
            theirs = mi.load_dict({"type": "bitmap", "filename": str(tmp_path / name), "format": fmt,
                                   "filter_type": "nearest"})
            want = []
            for u in uv:
                si.uv = mi.Point2f(*u)
                want.append(np.array(theirs.eval(si)))
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
    si = mi.SurfaceInteraction3f()
    uv = np.stack(np.meshgrid((np.arange(7) + 0.5) / 7, (np.arange(5) + 0.5) / 5), -1).reshape(-1, 2)
    checked = 0
    for path, _, _ in image_files:
        if path.suffix in (".tif", ".pgm") or path.name == "rgb16.ppm":
            continue
        for raw in (False, True):
            theirs = mi.load_dict({"type": "bitmap", "filename": str(path), "raw": raw, "filter_type": "nearest"})
            want = []
            for u in uv:
                si.uv = mi.Point2f(*u)
                want.append(np.array(theirs.eval(si)))
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
    (tmp_path / "short.pfm").write_bytes(b"PF\n4 4\n-1\n" + bytes(20))
    with pytest.raises(SceneError, match="ends before its 4 x 4 pixels"):
        bitmap(tmp_path / "short.pfm")
    (tmp_path / "short.ppm").write_bytes(b"P6\n4 4\n65535\n" + bytes(20))
    with pytest.raises(SceneError, match="ends before its 48 samples"):
        bitmap(tmp_path / "short.ppm")
