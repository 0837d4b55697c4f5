"""Analytic sphere (the ETH variant of Nori), intersected exactly in the kernel.

```xml
<mesh type="sphere">
    <point name="center" value="0, 0, 0"/>   <!-- default 0,0,0 -->
    <float name="radius" value="1"/>         <!-- default 1 -->
</mesh>
```
Normals point outward; uv = (atan2(n.y, n.x) / 2pi wrapped to [0,1), acos(n.z) / pi).
Tables (kernels/shapes/sphere.h): one row of `spheres` (centre, radius) and of `sphere_shape` (this shape); the
row's first is that row. An emitting sphere is sampled analytically (the cone it subtends), so it has no CDF.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .shape import Shape


@register("mesh", "sphere")
class Sphere(Shape):
    kernel = "shapes/sphere.h"
    is_sphere = True

    def __init__(self, props, children, spec):
        self.center = np.asarray(props.get_point("center", np.zeros(3)), np.float64)
        self.radius = float(props.get_float("radius", 1.0))
        if not np.all(np.isfinite(self.center)):
            raise SceneError(f"sphere center must be finite, got {self.center}", props.location("center"))
        if not (self.radius > 0 and np.isfinite(self.radius)):
            raise SceneError(f"sphere radius must be a positive number, got {self.radius}", spec.location)
        self._attach(children, spec)

    def area(self) -> float:
        return 4.0 * np.pi * self.radius ** 2

    def fill(self, ctx, index, row):
        row["first"] = ctx.add_table("spheres", "float4", [[*self.center, self.radius]])
        ctx.add_table("sphere_shape", "uint", [index])
        row["count"] = 1
        row["flags"] = 0

    def area_distribution(self):
        return None, self.area()
