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

from ..errors import SceneError
from ..scene.registry import register
from .emitter import Emitter, nonnegative_color


@register("emitter", "area")
class AreaEmitter(Emitter):
    kernel = "emitters/area.h"
    PARAMS = [("radiance", "float4")]
    FLAGS = ("SURFACE",)

    def __init__(self, props, children, spec):
        self.radiance = nonnegative_color(props, "radiance")

    def fill(self, p, row, ctx, shape):
        p["radiance"][:3] = self.radiance
@register("emitter", "area", fmt="mitsuba")
class MitsubaAreaEmitter(AreaEmitter):
    """Mitsuba 3's area light, nested in (or referenced by) a shape: one-sided, on the side its normals face.

    ```xml
    <shape type="obj">
        ...
        <emitter type="area">
            <rgb name="radiance" value="10, 10, 10"/>   <!-- required; rgb, spectrum (emitter convention) or float -->
        </emitter>
    </shape>
    ```
    """

    def __init__(self, props, children, spec):
        c = np.asarray(props.get_color("radiance", emitter=True), np.float64)
        if np.any(c < 0) or not np.all(np.isfinite(c)):
            raise SceneError(f"radiance must be non-negative and finite, got {c.tolist()}", props.location("radiance"))
        self.radiance = c
