"""Point light: a delta light at `position` radiating the flux `power` evenly, i.e. with intensity
I = Φ / (4π) in every direction; a surface at distance d receives I cosθ / d².

```xml
<emitter type="point">
    <point name="position" value="0, 2, 0"/>     <!-- default 0, 0, 0 -->
    <color name="power" value="100, 100, 100"/>  <!-- required: flux Φ in watts (a single number is grey) -->
</emitter>
```
Emitter row (kernels/emitters/point.h): p.point: intensity.xyz = I = Φ/(4π); position.xyz; power.xyz = Φ.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from ..scene.xmlbase import FLOAT_MAX
from .emitter import Emitter, luminance, nonnegative_color


@register("emitter", "point")
class PointEmitter(Emitter):
    kernel = "emitters/point.h"
    PARAMS = [("intensity", "float4"), ("position", "float4"), ("power", "float4")]
    FLAGS = ("DELTA",)
    METHODS = ("sample",)

    def __init__(self, props, children, spec):
        self.position = np.asarray(props.get_point("position", np.zeros(3)), np.float64)
        if not np.all(np.isfinite(self.position)):
            raise SceneError(f"position must be finite, got {self.position.tolist()}", props.location("position"))
        self.power = nonnegative_color(props, "power")

    @property
    def intensity(self) -> np.ndarray:
        return self.power / (4.0 * np.pi)

    def selection_power(self, radius, area):
        return luminance(self.power)

    def fill(self, p, row, ctx, shape):
        p["intensity"][:3] = self.intensity
        p["position"][:3] = self.position
        p["power"][:3] = self.power


@register("emitter", "point", fmt="mitsuba")
class MitsubaPoint(PointEmitter):
    """Mitsuba 3's point light: the radiant intensity I is given (not the flux), the position by `position` or by
    the translation of `to_world`.

    ```xml
    <emitter type="point">
        <point name="position" value="0, 2, 0"/>   <!-- or <transform name="to_world">; default the origin -->
        <rgb name="intensity" value="10"/>          <!-- W/sr, default 1 -->
    </emitter>
    ```
    """

    def __init__(self, props, children, spec):
        if props.has("position") and props.has("to_world"):
            raise SceneError("give either position or to_world, not both", props.location("position"))
        if props.has("to_world"):
            self.position = props.get_transform("to_world").apply_point(np.zeros(3))
        else:
            self.position = np.asarray(props.get_point("position", np.zeros(3)), np.float64)
        if not np.all(np.isfinite(self.position)):
            raise SceneError(f"position must be finite, got {self.position.tolist()}", props.location("position"))
        self.power = 4.0 * np.pi * nonnegative_color(props, "intensity", np.ones(3), emitter=True)
        if not self.power.max() <= FLOAT_MAX:  # packed as float32: it would be infinite
            raise SceneError(f"intensity {self.intensity.max():g} is too large: its power (4 pi times it) exceeds "
                             f"{FLOAT_MAX:.4g}, the largest single-precision number",
                             props.location("intensity"))
