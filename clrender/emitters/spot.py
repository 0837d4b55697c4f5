"""Mitsuba 3's spot light: a point light at the origin of `to_world` shining along its local +z, with the full
intensity I inside `beam_width` and a falloff linear in the angle down to 0 at `cutoff_angle`.

```xml
<emitter type="spot">
    <rgb name="intensity" value="20"/>           <!-- W/sr at the centre, default 1 -->
    <float name="cutoff_angle" value="30"/>     <!-- degrees, default 20 -->
    <float name="beam_width" value="20"/>       <!-- degrees, default cutoff_angle * 3/4 -->
    <transform name="to_world">
        <lookat origin="0, 4, 0" target="0, 0, 0" up="0, 0, 1"/>
    </transform>
</emitter>
```
The falloff of a direction d leaving the light (Mitsuba's, from its plugin documentation): with θ the angle
between normalize(to_world⁻¹ d) and +z, 1 for θ <= beam_width, (cutoff − θ) / (cutoff − beam_width) between,
and 0 for θ >= cutoff. A surface at distance r receives I · falloff · cosθ_surface / r².

Emitter row (kernels/emitters/spot.h): p.spot: intensity.xyz; position.xyz, position.w = 1 / (cutoff − beam
width) (radians; 0 when they are equal); inv[0..2].xyz = the rows of the inverse of to_world's linear part,
inv[0].w = cos(cutoff), inv[1].w = cos(beam width), inv[2].w = cutoff in radians.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .emitter import Emitter, luminance, nonnegative_color


@register("emitter", "spot", fmt="mitsuba")
class SpotEmitter(Emitter):
    kernel = "emitters/spot.h"
    PARAMS = [("intensity", "float4"), ("position", "float4"), ("inv", "float4", 3)]
    FLAGS = ("DELTA",)
    METHODS = ("sample",)

    def __init__(self, props, children, spec):
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

    def selection_power(self, radius, area):
        # the solid angle of the cone out to the middle of the falloff ramp
        half = np.radians(0.5 * (self.cutoff + self.beam_width))
        return 2.0 * np.pi * (1.0 - np.cos(half)) * luminance(self.intensity)

    def fill(self, p, row, ctx, shape):
        c, b = np.radians(self.cutoff), np.radians(self.beam_width)
        p["intensity"][:3] = self.intensity
        p["position"] = (*self.position, 1.0 / (c - b) if c > b else 0.0)
        for k in range(3):
            p["inv"][k][:3] = self.inverse_linear[k]
        p["inv"][0][3], p["inv"][1][3], p["inv"][2][3] = np.cos(c), np.cos(b), c
