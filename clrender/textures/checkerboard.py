"""Mitsuba 3's checkerboard texture: two colours in a 2 x 2 pattern per unit square of (transformed) uv.

```xml
<bsdf type="diffuse">
    <texture type="checkerboard" name="reflectance">
        <rgb name="color0" value="0.8"/>                           <!-- default 0.4 -->
        <rgb name="color1" value="0.1, 0.2, 0.3"/>                 <!-- default 0.2 -->
        <transform name="to_uv"><scale x="4" y="4"/></transform>   <!-- default identity -->
    </texture>
</bsdf>
```
Mitsuba's pattern (from its plugin source; checked against Mitsuba 3.9.1's own `checkerboard`): with st =
to_uv(uv), color0 where (frac(s) > ½) == (frac(t) > ½), color1 elsewhere, so [0, ½)² is color0. The colours are
constants here (Mitsuba also allows nested textures: not supported).

Where a float parameter takes the texture (a roughness, a blend weight, an opacity), Mitsuba 3.9.1's `eval_1`
gives the mean of color1's channels where `eval` gives color0, and the mean of color0's where it gives color1 (its
float lookup tests the cells the other way round; checked against Mitsuba's own), and so does clrender.

Texture row (kernels/textures/checkerboard.h): p.checkerboard.c0 = (color0, to_uv a), c1 = (color1, to_uv b),
uv2 = (to_uv c, d, e, f) for s = a u + b v + c, t = d u + e v + f.
"""
import copy

import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .bitmap import uv_transform
from .texture import Texture


@register("texture", "checkerboard", fmt="mitsuba")
class Checkerboard(Texture):
    kernel = "textures/checkerboard.h"
    PARAMS = [("c0", "float4"), ("c1", "float4"), ("uv2", "float4")]

    def __init__(self, props, children, spec):
        self.color0 = np.asarray(props.get_color("color0", np.full(3, 0.4)), np.float64)
        self.color1 = np.asarray(props.get_color("color1", np.full(3, 0.2)), np.float64)
        for name, v in (("color0", self.color0), ("color1", self.color1)):
            if np.any(v < 0) or not np.all(np.isfinite(v)):
                raise SceneError(f"{name} must be non-negative, got {v.tolist()}", props.location(name))
        self.to_uv = uv_transform(props)

    def max_value(self) -> float:
        return float(max(self.color0.max(), self.color1.max()))

    def make_float_view(self) -> "Checkerboard":
        view = copy.copy(self)
        view.color0 = np.full(3, self.color1.mean())
        view.color1 = np.full(3, self.color0.mean())
        view.__dict__["_float_view"] = view
        return view

    def eval(self, uv) -> np.ndarray:
        uv = np.asarray(uv, np.float64)
        st = uv @ self.to_uv[:, :2].T + self.to_uv[:, 2]
        m = (st - np.floor(st)) > 0.5
        return np.where((m[..., 0] == m[..., 1])[..., None], self.color0, self.color1)

    def fill(self, p) -> None:
        m = self.to_uv
        p["c0"] = (*self.color0, m[0, 0])
        p["c1"] = (*self.color1, m[0, 1])
        p["uv2"] = (m[0, 2], m[1, 0], m[1, 1], m[1, 2])
