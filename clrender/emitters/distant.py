"""Distant (directional) light, an extension (like Mitsuba's `directional` and pbrt's `distant`): parallel
light travelling along `direction`, delivering the irradiance `irradiance` to a surface perpendicular to it.
A delta light: it is reached only by explicit sampling, never by a ray.

```xml
<emitter type="distant">
    <vector name="direction" value="0.4, -1, -0.5"/>   <!-- required: the way the light travels -->
    <color name="irradiance" value="1, 1, 1"/>         <!-- required: E in W/m² (a single number is grey) -->
</emitter>
```
Emitter row (kernels/emitters/distant.h): p.distant.irradiance.xyz = E; p.distant.direction.xyz = the unit
direction of travel.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .emitter import Emitter, nonnegative_color


@register("emitter", "distant")
class DistantEmitter(Emitter):
    kernel = "emitters/distant.h"
    PARAMS = [("irradiance", "float4"), ("direction", "float4")]
    FLAGS = ("DELTA",)
    METHODS = ("sample",)

    def __init__(self, props, children, spec):
        d = np.asarray(props.get_vector("direction"), np.float64)
        n = float(np.linalg.norm(d))
        if not (np.isfinite(n) and n > 0):
            raise SceneError(f"direction must be a non-zero vector, got {d.tolist()}", props.location("direction"))
        self.direction = d / n
        self.irradiance = nonnegative_color(props, "irradiance")

    def fill(self, p, row, ctx, shape):
        p["irradiance"][:3] = self.irradiance
        p["direction"][:3] = self.direction
