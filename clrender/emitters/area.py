"""Area light on a mesh or sphere (nested in its `<mesh>`): uniform radiance on the side its shading normal
faces (one-sided). Points are sampled by picking a triangle in proportion to its area, then a uniform point
on it; the area density is converted to solid angle with dist² / |cos at the light|.

```xml
<mesh type="obj">
    <string name="filename" value="light.obj"/>
    <emitter type="area">
        <color name="radiance" value="10, 10, 10"/>   <!-- required -->
    </emitter>
</mesh>
```
Emitter row (kernels/emitters/area.h): p.area.radiance.xyz = radiance, shape = the emitting shape, which
samples its own surface (its area distribution is packed with it: clrender/shapes/shape.py).
"""
import numpy as np

from ..scene.registry import register
from .emitter import Emitter, luminance, nonnegative_color


@register("emitter", "area")
class AreaEmitter(Emitter):
    kernel = "emitters/area.h"
    PARAMS = [("radiance", "float4")]
    FLAGS = ("SURFACE",)

    def __init__(self, props, children, spec):
        self.radiance = nonnegative_color(props, "radiance")

    def fill(self, p, row, ctx, shape):
        p["radiance"][:3] = self.radiance

    def selection_power(self, radius, area):
        return np.pi * area * luminance(self.radiance)   # one-sided Lambertian emitter
