"""Mitsuba 3's spot light: a point light at the origin of `to_world` shining along its local +z, with the full
intensity I inside `beam_width` and a falloff linear in the angle down to 0 at `cutoff_angle`.

```xml
<emitter type="spot">
    <rgb name="intensity" value="20"/>           <!-- W/sr at the centre, default 1 -->
    <float name="cutoff_angle" value="30"/>     <!-- degrees, default 20 -->
    <float name="beam_width" value="20"/>       <!-- degrees, default cutoff_angle * 3/4 -->
    <texture type="bitmap" name="texture">      <!-- optional: an image projected by the light -->
        <string name="filename" value="slide.png"/>
    </texture>
    <transform name="to_world">
        <lookat origin="0, 4, 0" target="0, 0, 0" up="0, 0, 1"/>
    </transform>
</emitter>
```
The falloff of a direction d leaving the light (Mitsuba's, from its plugin documentation): with θ the angle
between normalize(to_world⁻¹ d) and +z, 1 for θ <= beam_width, (cutoff − θ) / (cutoff − beam_width) between,
and 0 for θ >= cutoff. A surface at distance r receives I · falloff · cosθ_surface / r².
With a `texture` (Mitsuba's projected image; it must vary in space, as Mitsuba requires: any of our textures
does), the intensity is multiplied by the texture at uv = (0.5 + 0.5 x / (z tan cutoff), 0.5 + 0.5 y / (z tan
cutoff)) of the local direction (x, y, z) leaving the light, as Mitsuba 3.9.1's spot.cpp computes it: the image
spans the square circumscribing the cutoff cone, so its corners fall outside the cone.

Emitter row (kernels/emitters/spot.h): p.spot: intensity.xyz, intensity.w = 1 / tan(cutoff); position.xyz,
position.w = 1 / (cutoff − beam width) (radians; 0 when they are equal); inv[0..2].xyz = the rows of the inverse of
to_world's linear part, inv[0].w = cos(cutoff), inv[1].w = cos(beam width), inv[2].w = cutoff in radians;
texture_tex = the texture's row or NONE.
"""
import numpy as np

from ..device import layout
from ..errors import SceneError
from ..scene.registry import register
from ..textures.texture import texture_child
from .emitter import Emitter, luminance, nonnegative_color


@register("emitter", "spot", fmt="mitsuba")
class SpotEmitter(Emitter):
    kernel = "emitters/spot.h"
    PARAMS = [("intensity", "float4"), ("position", "float4"), ("inv", "float4", 3), ("texture_tex", "uint")]
    FLAGS = ("DELTA",)
    METHODS = ("sample",)
    children = ("texture",)

    def __init__(self, props, children, spec):
        self.texture = texture_child(children, "texture", '<emitter type="spot">')
        self.intensity = nonnegative_color(props, "intensity", np.ones(3), emitter=True)
        self.cutoff = float(props.get_float("cutoff_angle", 20.0))
        self.beam_width = float(props.get_float("beam_width", self.cutoff * 0.75))
        if not (0.0 < self.cutoff <= 180.0):
            raise SceneError(f"cutoff_angle must be in (0, 180] degrees, got {self.cutoff:g}",
                             props.location("cutoff_angle"))
        if not (0.0 <= self.beam_width <= self.cutoff):
            raise SceneError(f"beam_width must be in [0, cutoff_angle = {self.cutoff:g}] degrees, got "
                             f"{self.beam_width:g}", props.location("beam_width"))
        t = props.get_transform("to_world")
        m = t.matrix[:3, :3]
        if not abs(np.linalg.det(m)) > 1e-12:
            raise SceneError("to_world must be invertible", props.location("to_world"))
        self.position = t.apply_point(np.zeros(3))
        self.inverse_linear = np.linalg.inv(m)

    def falloff(self, d_world) -> np.ndarray:
        """The falloff of world directions (..., 3) leaving the light (a host reference for tests)."""
        local = np.asarray(d_world, np.float64) @ self.inverse_linear.T
        local = local / np.linalg.norm(local, axis=-1, keepdims=True)
        theta = np.arccos(np.clip(local[..., 2], -1, 1))
        c, b = np.radians(self.cutoff), np.radians(self.beam_width)
        ramp = (c - theta) / (c - b) if c > b else np.zeros_like(theta)
        inner = np.where(local[..., 2] >= np.cos(b), 1.0, ramp)
        return np.where(local[..., 2] > np.cos(c), inner, 0.0)

    def uv(self, d_world) -> np.ndarray:
        """The texture coordinates of world directions (..., 3) leaving the light (host reference for tests)."""
        local = np.asarray(d_world, np.float64) @ self.inverse_linear.T
        k = 0.5 / np.tan(np.radians(self.cutoff))
        return np.stack([0.5 + k * local[..., 0] / local[..., 2], 0.5 + k * local[..., 1] / local[..., 2]], axis=-1)

    def selection_power(self, radius, area):
        # the solid angle of the cone out to the middle of the falloff ramp; a texture with its largest value
        half = np.radians(0.5 * (self.cutoff + self.beam_width))
        scale = self.texture.max_value() if self.texture is not None else 1.0
        return 2.0 * np.pi * (1.0 - np.cos(half)) * luminance(self.intensity) * scale

    def fill(self, p, row, ctx, shape):
        c, b = np.radians(self.cutoff), np.radians(self.beam_width)
        p["intensity"][:3] = self.intensity
        p["intensity"][3] = 1.0 / np.tan(c) if c < np.pi / 2 else 0.0   # beyond 90 degrees uv is undefined
        p["texture_tex"] = layout.NONE if self.texture is None else ctx.textures.add(self.texture)
        p["position"] = (*self.position, 1.0 / (c - b) if c > b else 0.0)
        for k in range(3):
            p["inv"][k][:3] = self.inverse_linear[k]
        p["inv"][0][3], p["inv"][1][3], p["inv"][2][3] = np.cos(c), np.cos(b), c
