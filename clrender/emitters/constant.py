"""Constant environment, an extension: the same radiance arrives from every direction (uniform sky,
furnace tests). Sampled uniformly on the sphere (pdf 1/(4π)).

```xml
<emitter type="constant">
    <color name="radiance" value="1, 1, 1"/>   <!-- required (a single number is grey) -->
</emitter>
```
Emitter row (kernels/emitters/constant.h): radiance.xyz = radiance.
"""
from ..device.layout import ENUMS
from ..scene.registry import register
from .emitter import Emitter, nonnegative_color


@register("emitter", "constant")
class ConstantEmitter(Emitter):
    emitter_type = ENUMS["EMITTER_CONSTANT"]
    is_infinite = True

    def __init__(self, props, children, spec):
        self.radiance = nonnegative_color(props, "radiance")

    def fill(self, row, ctx, shape):
        row["radiance"][:3] = self.radiance
