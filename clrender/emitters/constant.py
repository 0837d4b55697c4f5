"""Constant environment, an extension: the same radiance arrives from every direction (uniform sky,
furnace tests). Sampled uniformly on the sphere (pdf 1/(4π)).

```xml
<emitter type="constant">
    <color name="radiance" value="1, 1, 1"/>   <!-- required (a single number is grey) -->
</emitter>
```
Emitter row (kernels/emitters/constant.h): p.constant_.radiance.xyz = radiance.
"""
import numpy as np

from ..scene.registry import register
from .emitter import Emitter, luminance, nonnegative_color


@register("emitter", "constant")
class ConstantEmitter(Emitter):
    kernel = "emitters/constant.h"
    PARAMS = [("radiance", "float4")]
    FLAGS = ("INFINITE",)

    def __init__(self, props, children, spec):
        self.radiance = nonnegative_color(props, "radiance")

    def fill(self, p, row, ctx, shape):
        p["radiance"][:3] = self.radiance

    def selection_power(self, radius, area):
        return np.pi * radius ** 2 * 4.0 * np.pi * luminance(self.radiance)   # through the scene's disk


@register("emitter", "constant", fmt="mitsuba")
class MitsubaConstant(ConstantEmitter):
    """Mitsuba 3's constant environment: the same, with radiance 1 by default.

    ```xml
    <emitter type="constant">
        <rgb name="radiance" value="0.5, 0.6, 0.7"/>   <!-- default 1 -->
    </emitter>
    ```
    """

    def __init__(self, props, children, spec):
        self.radiance = nonnegative_color(props, "radiance", np.ones(3), emitter=True)
