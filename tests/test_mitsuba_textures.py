"""Mitsuba 3 textures (clrender/textures/bitmap.py, checkerboard.py) evaluated by the kernels against their host
references (numpy), which were checked against Mitsuba 3.9.1's own plugins (see their docstrings): bitmap texel
lookup for every filter and wrap mode, with and without sRGB decoding and a to_uv transform; the checkerboard
pattern; known sRGB values; errors."""
import numpy as np
import pyopencl as cl
import pytest
from PIL import Image

from clrender.device.program import build_program
from clrender.errors import SceneError
from clrender.scene import registry
from clrender.scene.transform import Transform
from clrender.textures.texture import TextureTable

SRC = r"""
#include "texture.h"
__kernel void tex_eval(__global const Texture* textures, uint idx, uint n, __global const float2* uv,
                       __global float4* out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    out[i] = (float4)(texture_eval(textures + idx, uv[i]), 0.0f);
}
"""


@pytest.fixture(scope="module")
def tex_kernel(ctx):
    return cl.Kernel(build_program(ctx, SRC), "tex_eval")


def device_eval(ctx, queue, kernel, textures, uv):
    """Evaluate every texture in `textures` (placed in one table, after a decoy) at uv (N, 2) on the device."""
    table = TextureTable()
    table.add(registry.instantiate("texture", "checkerboard", {}, fmt="mitsuba"))   # not at row 0
    rows = [table.add(t) for t in textures]
    arr = table.array()
    ro = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
    tbuf = cl.Buffer(ctx, ro, hostbuf=arr)
    uv = np.ascontiguousarray(uv, np.float32)
    ubuf = cl.Buffer(ctx, ro, hostbuf=uv)
    n = len(uv)
    obuf = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, size=n * 16)
    outs = []
    for r in rows:
        kernel(queue, ((n + 63) // 64 * 64,), (64,), tbuf, np.uint32(r), np.uint32(n), ubuf, obuf)
        out = np.empty((n, 4), np.float32)
        cl.enqueue_copy(queue, out, obuf)
        outs.append(out[:, :3])
    return outs


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
def test_bitmap_lookup_matches_host(ctx, queue, tex_kernel, png, filt, wrap):
    path, _ = png
    texs = [bitmap(path, filter_type=filt, wrap_mode=wrap), bitmap(path, filter_type=filt, wrap_mode=wrap, raw=True),
            bitmap(path, filter_type=filt, wrap_mode=wrap, to_uv=TO_UV)]
    uv = np.random.default_rng(5).uniform(-2.5, 3.5, size=(3000, 2))
    # also exact texel centres and edges, where nearest and bilinear switch
    g = np.stack(np.meshgrid(np.arange(-7, 15) / 7.0, np.arange(-5, 11) / 5.0), -1).reshape(-1, 2) + 1e-4
    uv = np.concatenate([uv, g])
    for t, dev in zip(texs, device_eval(ctx, queue, tex_kernel, texs, uv)):
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


def test_checkerboard_pattern(ctx, queue, tex_kernel):
    c0, c1 = [0.9, 0.1, 0.2], [0.05, 0.3, 0.7]
    t = registry.instantiate("texture", "checkerboard", {"color0": ("color", c0), "color1": ("color", c1),
                                                        "to_uv": ("transform", Transform.scale([3, 2, 1]))},
                             fmt="mitsuba")
    # [0, 1/2)^2 of st is color0; st = (3u, 2v)
    pts = np.array([[0.1 / 3, 0.1 / 2], [0.6 / 3, 0.1 / 2], [0.6 / 3, 0.6 / 2], [0.1 / 3, 0.6 / 2], [1.1 / 3, 0.1 / 2],
                    [-0.4 / 3, 0.1 / 2]])
    expect = np.array([c0, c1, c0, c1, c0, c1])
    np.testing.assert_allclose(t.eval(pts), expect)
    uv = np.concatenate([pts, np.random.default_rng(6).uniform(-3, 3, size=(4000, 2))])
    dev = device_eval(ctx, queue, tex_kernel, [t], uv)[0]
    host = t.eval(uv)
    # points within float rounding of a cell edge may land either side
    st = uv @ t.to_uv[:, :2].T + t.to_uv[:, 2]
    frac = st - np.floor(st)
    clear = np.all(np.minimum(np.abs(frac - 0.5), np.minimum(frac, 1 - frac)) > 1e-5, axis=1)
    np.testing.assert_allclose(dev[clear], host[clear], atol=1e-7)
    np.testing.assert_allclose(dev[:6], expect, atol=1e-7)
    dflt = registry.instantiate("texture", "checkerboard", {}, fmt="mitsuba")
    np.testing.assert_allclose(dflt.eval([[0.2, 0.2], [0.7, 0.2]]), [[0.4] * 3, [0.2] * 3])


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


def test_16_bit_grey_png_is_read(tmp_path):
    # It used to be refused ("only 8-bit ... images"); Mitsuba reads it, sRGB-decoded unless raw like 8-bit ones.
    from PIL import Image

    from clrender.textures.imagefile import read_image, srgb_to_linear

    values = (np.arange(12).reshape(3, 4) * 5000).astype(np.uint16)
    Image.fromarray(values).save(tmp_path / "g.png")
    raw = read_image(tmp_path / "g.png", raw=True)
    assert raw.shape == (3, 4, 3)
    np.testing.assert_allclose(raw[..., 1], values / 65535.0, rtol=1e-6)
    np.testing.assert_allclose(read_image(tmp_path / "g.png")[..., 0], srgb_to_linear(values / 65535.0), rtol=1e-5)
