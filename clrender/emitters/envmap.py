"""Mitsuba 3's environment map: radiance from a latitude-longitude image (EXR or Radiance HDR) at infinity,
importance sampled by a 2-D piecewise-constant distribution over the image.

```xml
<emitter type="envmap">
    <string name="filename" value="sky.exr"/>   <!-- required: an image file that `bitmap` reads -->
    <float name="scale" value="1"/>             <!-- multiplies the radiance, default 1 -->
    <transform name="to_world">                 <!-- a rotation, default identity -->
        <rotate y="1" angle="90"/>
    </transform>
</emitter>
```
Conventions (Mitsuba's, from its plugin sources): a map narrower than 2 or lower than 3 pixels is first padded to
that size by repeating its last column and its last row (Mitsuba 3.9.1's `Bitmap::pad_to`), so a 1 x 1 map is a
constant sky. A world direction d maps to local v = to_world⁻¹ d, and to
uv = (atan2(v.x, -v.z) / 2π, acos(v.y) / π): +y is up, row 0 of the image is the zenith, the last row the nadir.
The image gets an extra column (a copy of the first) so that it is periodic in u, and the radiance is the bilinear
interpolation of those W+1 by H pixel values at x = W (u − ½/W mod 1), y = (H − 1) v, times `scale`: pixel
centres sit at u = (i + ½) / W horizontally, rows at v = j / (H − 1) vertically.

Sampling: the (W x (H − 1)) cells between those pixel values get the weight mean(corner luminances) · sin θ
at the cell's centre (never 0 where the radiance is not); a row is picked from the marginal CDF, a cell from that
row's conditional CDF, and a point in the cell with density proportional to the bilinear patch of its corner
luminances (clamped at 0; uniform in a black cell), as the radiance varies there (Mitsuba's envmap warp does the
same; drawing uniformly in the cell left a lone bright texel 4.8 times Mitsuba's per-pixel noise). Its density in
uv is pmf · W (H − 1) · bilinear / mean(corners), in solid angle that divided by 2π² sin θ (θ = π v at the point).

Emitter row (kernels/emitters/envmap.h): p.envmap.dims = (first texel row in the textures table, W, H, offset of
the CDFs in the `cdf` table: H − 1 marginal values, then H − 1 conditional CDFs of W values); inv[0..2].xyz =
rows of to_world⁻¹'s rotation, inv[0].w = scale.
"""
from pathlib import Path

import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from ..textures.imagefile import read_image
from .emitter import LUMINANCE, Emitter


def pad_to(img: np.ndarray, width: int, height: int) -> np.ndarray:
    """img grown to at least width x height by repeating its last column, then its last row (as Mitsuba's
    `Bitmap::pad_to`): the lookup below needs two columns and two cells of latitude."""
    h, w = img.shape[:2]
    return np.pad(img, ((0, max(height - h, 0)), (0, max(width - w, 0)), (0, 0)), mode="edge")


@register("emitter", "envmap", fmt="mitsuba")
class EnvMap(Emitter):
    kernel = "emitters/envmap.h"
    PARAMS = [("dims", "uint4"), ("inv", "float4", 3)]
    FLAGS = ("INFINITE",)

    def __init__(self, props, children, spec):
        path = Path(props.get_string("filename"))   # the reader resolved it against the scene's folder
        self.image = pad_to(read_image(path, location=props.location("filename"), half=False), 2, 3)
        if np.any(self.image < 0):
            raise SceneError(f"'{path.name}': an environment map cannot hold negative radiance",
                             props.location("filename"))
        self.scale = float(props.get_float("scale", 1.0))
        if not (np.isfinite(self.scale) and self.scale >= 0):
            raise SceneError(f"scale must be non-negative, got {self.scale:g}", props.location("scale"))
        m = props.get_transform("to_world").matrix[:3, :3]
        if not np.allclose(m @ m.T, np.eye(3), atol=1e-5):
            raise SceneError("an environment map's to_world must be a rotation (no scale or shear)",
                             props.location("to_world"))
        self._setup(self.image, self.scale, m)

    @classmethod
    def from_image(cls, image: np.ndarray, to_world: np.ndarray, scale: float = 1.0) -> "EnvMap":
        """An environment map made by code rather than read from a file (the sunsky's sky): `image` (H, W, 3),
        non-negative; `to_world` a 3x3 rotation."""
        em = cls.__new__(cls)
        em._setup(pad_to(np.asarray(image, np.float32), 2, 3), float(scale), np.asarray(to_world, np.float64))
        return em

    def _setup(self, image: np.ndarray, scale: float, to_world: np.ndarray) -> None:
        self.image, self.scale, self.to_world = image, scale, to_world
        self.data = np.concatenate([self.image, self.image[:, :1]], axis=1)   # periodic in u: W+1 columns
        self.marginal, self.conditional = self._distribution()

    def _distribution(self):
        h, w1 = self.data.shape[:2]
        lum = self.data.astype(np.float64) @ LUMINANCE
        cell = 0.25 * (lum[:-1, :-1] + lum[:-1, 1:] + lum[1:, :-1] + lum[1:, 1:])     # (H-1, W)
        theta = (np.arange(h - 1) + 0.5) * np.pi / (h - 1)
        cell = cell * np.sin(theta)[:, None]
        rows = cell.sum(axis=1)
        if not rows.sum() > 0:   # a black map: any density will do
            cell = np.ones_like(cell)
            rows = cell.sum(axis=1)
        safe = np.where(rows > 0, rows, 1.0)
        cond = np.where(rows[:, None] > 0, np.cumsum(cell, axis=1) / safe[:, None],
                        (np.arange(1, w1) / (w1 - 1))[None, :])
        cond[:, -1] = 1.0
        marg = np.cumsum(rows) / rows.sum()
        marg[-1] = 1.0
        return marg.astype(np.float32), cond.astype(np.float32)

    # ---- host references (tests) ----
    def eval(self, d_world) -> np.ndarray:
        """Radiance arriving from world directions (..., 3)."""
        h, w1 = self.data.shape[:2]
        w = w1 - 1
        v = np.asarray(d_world, np.float64) @ self.to_world    # = to_world^T d
        v = v / np.linalg.norm(v, axis=-1, keepdims=True)
        u = np.arctan2(v[..., 0], -v[..., 2]) / (2 * np.pi) - 0.5 / w
        u = u - np.floor(u)
        t = np.arccos(np.clip(v[..., 1], -1, 1)) / np.pi
        x, y = u * w, t * (h - 1)
        ix, iy = np.minimum(x.astype(int), w - 1), np.minimum(y.astype(int), h - 2)
        fx, fy = (x - ix)[..., None], (y - iy)[..., None]
        d = self.data.astype(np.float64)
        top = d[iy, ix] * (1 - fx) + d[iy, ix + 1] * fx
        bot = d[iy + 1, ix] * (1 - fx) + d[iy + 1, ix + 1] * fx
        return (top * (1 - fy) + bot * fy) * self.scale

    def selection_power(self, radius, area):
        # radiance integrated over the sphere: the mean of the cells' luminance weighted by their solid angle
        lum = self.data[:, :-1].astype(np.float64) @ LUMINANCE
        h = lum.shape[0]
        theta = np.arange(h) * np.pi / (h - 1)
        band = np.sin(theta)
        flux = (lum * band[:, None]).sum() / (band.sum() * lum.shape[1]) * 4.0 * np.pi
        return np.pi * radius ** 2 * self.scale * flux

    def fill(self, p, row, ctx, shape, extra_texels=None):
        """`extra_texels` (N, 4): rows stored right after the map's texels (the sunsky's model coefficients)."""
        h, w1 = self.data.shape[:2]
        px = np.zeros((h * w1, 4), np.float32)
        px[:, :3] = self.data.reshape(-1, 3)
        if extra_texels is not None:
            px = np.concatenate([px, np.asarray(extra_texels, np.float32).reshape(-1, 4)])
        first = ctx.textures.add_texels(px)
        cdf = ctx.add_table("cdf", "float", np.concatenate([self.marginal, self.conditional.reshape(-1)]))
        p["dims"] = (first, w1 - 1, h, cdf)
        inv = self.to_world.T
        for k in range(3):
            p["inv"][k][:3] = inv[k]
        p["inv"][0][3] = self.scale
