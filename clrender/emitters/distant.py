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
from .emitter import Emitter, luminance, nonnegative_color


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

    def selection_power(self, radius, area):
        return np.pi * radius ** 2 * luminance(self.irradiance)


@register("emitter", "directional", fmt="mitsuba")
class MitsubaDirectional(DistantEmitter):
    """Mitsuba 3's directional light: irradiance E (default 1) travelling along `direction`, or along the image of
    local +z under `to_world`.

    ```xml
    <emitter type="directional">
        <vector name="direction" value="0, -1, 0"/>   <!-- or <transform name="to_world">; default +z -->
        <rgb name="irradiance" value="3"/>            <!-- W/m², default 1 -->
    </emitter>
    ```
    """

    def __init__(self, props, children, spec):
        if props.has("direction") and props.has("to_world"):
            raise SceneError("give either direction or to_world, not both", props.location("direction"))
        if props.has("to_world"):
            d, where = props.get_transform("to_world").apply_vector([0.0, 0.0, 1.0]), "to_world"
        else:
            d, where = np.asarray(props.get_vector("direction", [0.0, 0.0, 1.0]), np.float64), "direction"
        n = float(np.linalg.norm(d))
        if not (np.isfinite(n) and n > 0):
            raise SceneError(f"the direction must be a non-zero vector, got {np.asarray(d).tolist()}",
                             props.location(where))
        self.direction = d / n
        self.irradiance = nonnegative_color(props, "irradiance", np.ones(3), emitter=True)
