"""Mitsuba 3's bitmap texture: an image (any format textures/imagefile.py reads: EXR, HDR, PFM, PNG, JPEG, BMP, TGA,
PPM, TIFF) looked up at the surface's uv.

```xml
<bsdf type="diffuse">
    <texture type="bitmap" name="reflectance">
        <string name="filename" value="wood.png"/>       <!-- required -->
        <string name="filter_type" value="bilinear"/>    <!-- bilinear (default) | nearest -->
        <string name="wrap_mode" value="repeat"/>        <!-- repeat (default) | mirror | clamp -->
        <boolean name="raw" value="false"/>              <!-- true: no sRGB decoding of 8/16-bit images -->
        <string name="format" value="auto"/>             <!-- auto (default) | variant | float16 | uint8 -->
        <transform name="to_uv"><scale x="2" y="2"/></transform>   <!-- default identity -->
    </texture>
</bsdf>
```
Conventions (Mitsuba's; checked against Mitsuba 3.9.1's own `bitmap` evaluated at random uvs, every filter and
wrap mode, with and without `raw` and `to_uv`): st = to_uv(uv), where a 4x4 `to_uv` acts on (u, v, 0, 1) and
keeps x and y; the image's first row is at t = 0 (no flip), pixel (i, j) covers s in [i/W, (i+1)/W). `nearest`
takes pixel floor(s W), floor(t H); `bilinear` interpolates the four pixels around (s W − ½, t H − ½). Pixel
indices outside the image wrap: `repeat` modulo the size, `mirror` reflected at the edges (…, 1, 0, 0, 1, …,
W−1, W−1, W−2, …), `clamp` to the edge. 8- and 16-bit images are sRGB-encoded and decoded to linear unless
`raw`; EXR, HDR and PFM are linear. Grey images give three equal channels; alpha is ignored. Where a float parameter takes
the texture (a roughness, a blend weight, an opacity), Mitsuba reads the luminance of the (decoded) colour.
`format` is the texels' storage as Mitsuba's (textures/imagefile.py says what each keeps; "fp16" is float16):
`auto` keeps 8 bits as bytes, 16 bits as half floats and float images as floats; `variant` float32 throughout;
`float16` rounds every value to half; `uint8` rounds every channel to a byte (clamped to [0, 1]).

Texture row (kernels/textures/bitmap.h): p.bitmap.dims = (W, H, filter: 0 bilinear / 1 nearest, wrap: 0 repeat /
1 mirror / 2 clamp); to_uv[0..1].xyz = the rows of the 2-D affine map; the W·H pixels (float4, row by row)
follow the row in the textures table.
"""
import copy
from pathlib import Path

import numpy as np

from ..emitters.emitter import LUMINANCE
from ..errors import SceneError
from ..scene.registry import register
from .imagefile import STORAGE, read_image
from .texture import Texture

FILTERS = ("bilinear", "nearest")
WRAPS = ("repeat", "mirror", "clamp")


def uv_transform(props, name="to_uv") -> np.ndarray:
    """The 2x3 affine map of a Mitsuba `to_uv` (a 4x4 transform acting on (u, v, 0, 1))."""
    m = props.get_transform(name).matrix
    if not (np.allclose(m[3, :2], 0) and m[3, 3] != 0):
        raise SceneError(f"{name} must be an affine map of uv", props.location(name))
    return np.array([[m[0, 0], m[0, 1], m[0, 3]], [m[1, 0], m[1, 1], m[1, 3]]]) / m[3, 3]


def choice(props, name, options, default):
    value = props.get_string(name, default)
    if value not in options:
        raise SceneError(f"{name} must be one of {', '.join(options)}; got '{value}'", props.location(name))
    return options.index(value)


def wrap_index(i, n, mode):
    """Pixel indices (integers, any range) wrapped into [0, n) by mode 0 repeat / 1 mirror / 2 clamp."""
    i = np.asarray(i, np.int64)
    if mode == 0:
        return np.mod(i, n)
    if mode == 1:
        k = np.mod(i, 2 * n)
        return np.where(k >= n, 2 * n - 1 - k, k)
    return np.clip(i, 0, n - 1)


@register("texture", "bitmap", fmt="mitsuba")
class Bitmap(Texture):
    kernel = "textures/bitmap.h"
    PARAMS = [("dims", "uint4"), ("to_uv", "float4", 2)]

    def __init__(self, props, children, spec):
        path = Path(props.get_string("filename"))   # the reader resolved it against the scene's folder
        self.raw = props.get_bool("raw", False)
        storage = props.get_string("format", "auto")
        storage = "float16" if storage == "fp16" else storage   # Mitsuba's old name, still read
        if storage not in STORAGE:
            raise SceneError(f"format must be one of {', '.join(STORAGE)}; got '{storage}'", props.location("format"))
        self.image = read_image(path, raw=self.raw, location=props.location("filename"), storage=storage)
        self.filter = choice(props, "filter_type", FILTERS, "bilinear")
        self.wrap = choice(props, "wrap_mode", WRAPS, "repeat")
        self.to_uv = uv_transform(props)

    def resolution(self) -> tuple[int, int]:
        h, w = self.image.shape[:2]
        return w, h

    def max_value(self) -> float:
        return float(self.image.max())

    def make_float_view(self) -> "Bitmap":
        # Mitsuba's bitmap eval_1 is the luminance of eval (linear in the texels, so taken per texel here)
        view = copy.copy(self)
        view.image = np.repeat((self.image.astype(np.float64) @ LUMINANCE)[..., None], 3, axis=-1)
        view.__dict__["_float_view"] = view
        return view

    def eval(self, uv) -> np.ndarray:
        """The colour at uv (..., 2) on the host (the reference the tests hold the kernel to)."""
        uv = np.asarray(uv, np.float64)
        st = uv @ self.to_uv[:, :2].T + self.to_uv[:, 2]
        h, w = self.image.shape[:2]
        img = self.image.astype(np.float64)
        if self.filter == 1:
            x = wrap_index(np.floor(st[..., 0] * w), w, self.wrap)
            y = wrap_index(np.floor(st[..., 1] * h), h, self.wrap)
            return img[y, x]
        fx, fy = st[..., 0] * w - 0.5, st[..., 1] * h - 0.5
        x0, y0 = np.floor(fx), np.floor(fy)
        a, b = (fx - x0)[..., None], (fy - y0)[..., None]
        xs = [wrap_index(x0, w, self.wrap), wrap_index(x0 + 1, w, self.wrap)]
        ys = [wrap_index(y0, h, self.wrap), wrap_index(y0 + 1, h, self.wrap)]
        top = img[ys[0], xs[0]] * (1 - a) + img[ys[0], xs[1]] * a
        bot = img[ys[1], xs[0]] * (1 - a) + img[ys[1], xs[1]] * a
        return top * (1 - b) + bot * b

    def eval_grad(self, uv) -> np.ndarray:
        """The uv gradient (..., 2) of the first channel as Mitsuba 3.9's eval_1_grad takes it (on the float view: the
        luminance) and kernels/textures/bitmap.h's bitmap_grad computes it: the bilinear interpolation's slope per
        pixel, through to_uv's transpose, times (W, H); 0 for `nearest`."""
        uv = np.asarray(uv, np.float64)
        h, w = self.image.shape[:2]
        if self.filter == 1:
            return np.zeros(uv.shape[:-1] + (2,))
        st = uv @ self.to_uv[:, :2].T + self.to_uv[:, 2]
        img = self.image[..., 0].astype(np.float64)
        fx, fy = st[..., 0] * w - 0.5, st[..., 1] * h - 0.5
        x0, y0 = np.floor(fx), np.floor(fy)
        a, b = fx - x0, fy - y0
        xa, xb = wrap_index(x0, w, self.wrap), wrap_index(x0 + 1, w, self.wrap)
        ya, yb = wrap_index(y0, h, self.wrap), wrap_index(y0 + 1, h, self.wrap)
        f00, f10, f01, f11 = img[ya, xa], img[ya, xb], img[yb, xa], img[yb, xb]
        dx = (1 - b) * (f10 - f00) + b * (f11 - f01)
        dy = (1 - a) * (f01 - f00) + a * (f11 - f10)
        m = self.to_uv
        return np.stack([w * (m[0, 0] * dx + m[1, 0] * dy), h * (m[0, 1] * dx + m[1, 1] * dy)], axis=-1)

    def fill(self, p) -> None:
        h, w = self.image.shape[:2]
        p["dims"] = (w, h, self.filter, self.wrap)
        for k in range(2):
            p["to_uv"][k][:3] = self.to_uv[k]

    def texels(self) -> np.ndarray:
        h, w = self.image.shape[:2]
        px = np.zeros((h * w, 4), np.float32)
        px[:, :3] = self.image.reshape(-1, 3)
        return px
