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

from ..device import dispatch
from ..errors import SceneError
from ..scene.registry import register
from .shape import SPHERE_EXTENT_MAX, Shape


@register("mesh", "sphere")
class Sphere(Shape):
    kernel = "shapes/sphere.h"

    def __init__(self, props, children, spec):
        self.center = np.asarray(props.get_point("center", np.zeros(3)), np.float64)
        self.radius = float(props.get_float("radius", 1.0))
        if not np.all(np.isfinite(self.center)):
            raise SceneError(f"sphere center must be finite, got {self.center}", props.location("center"))
        if not (self.radius > 0 and np.isfinite(self.radius)):
            raise SceneError(f"sphere radius must be a positive number, got {self.radius}", spec.location)
        self._check_extent(spec)
        self._attach(children, spec)

    def _check_extent(self, spec) -> None:
        if float(np.abs(self.center).max()) + self.radius > SPHERE_EXTENT_MAX:
            raise SceneError(f"sphere (center {self.center.tolist()}, radius {self.radius:g}) reaches beyond "
                             f"{SPHERE_EXTENT_MAX:g}: the single-precision intersection test may overflow "
                             f"and miss it", spec.location)

    def area(self) -> float:
        return 4.0 * np.pi * self.radius ** 2

    def fill(self, ctx, index, row):
        row["first"] = ctx.add_table("spheres", "float4", [[*self.center, self.radius]])
        ctx.add_table("sphere_shape", "uint", [index])
        row["count"] = 1
        row["flags"] = 0

    def area_distribution(self):
        return None, self.area()


@register("shape", "sphere", fmt="mitsuba")
class MitsubaSphere(Sphere):
    """Mitsuba 3's analytic ``sphere``: the sphere of ``radius`` about ``center``, then ``to_world`` (which may
    rotate, translate and scale uniformly; Mitsuba forbids non-uniform scales and shears, and so do we).
    uv = (phi / 2pi, theta / pi) as above (the same as Mitsuba's).

    ```xml
    <shape type="sphere">
        <point name="center" value="0, 0, 0"/>         <!-- default 0, 0, 0 -->
        <float name="radius" value="1"/>               <!-- default 1 -->
        <transform name="to_world"> ... </transform>   <!-- default identity -->
        <boolean name="flip_normals" value="false"/>   <!-- default false: normals point outward -->
        <bsdf type="..."/>  <emitter type="area"> ... </emitter>
    </shape>
    ```
    """

    def __init__(self, props, children, spec):
        center = np.asarray(props.get_point("center", np.zeros(3)), np.float64)
        radius = float(props.get_float("radius", 1.0))
        m = np.asarray(props.get_transform("to_world").matrix, np.float64)
        self.flip_normals = props.get_bool("flip_normals", False)
        if not (np.all(np.isfinite(center)) and np.isfinite(radius) and radius > 0):
            raise SceneError(f"sphere needs a finite center and a positive radius, got {center.tolist()}, {radius}",
                             spec.location)
        lin = m[:3, :3]
        scales = np.linalg.norm(lin, axis=0)
        gram = lin.T @ lin
        if (not np.all(np.isfinite(m)) or np.any(m[3] != [0, 0, 0, 1]) or scales.min() <= 0
                or np.abs(gram - np.diag(np.diag(gram))).max() > 1e-5 * scales.max() ** 2
                or scales.max() - scales.min() > 1e-5 * scales.max()):
            raise SceneError("a sphere's to_world may only rotate, translate and scale uniformly (Mitsuba forbids "
                             "non-uniform scales and shears)", props.location("to_world") or spec.location)
        self.center = lin @ center + m[:3, 3]
        self.radius = radius * float(scales.mean())
        self._check_extent(spec)
        self._attach(children, spec)

    def fill(self, ctx, index, row):
        super().fill(ctx, index, row)
        if self.flip_normals:
            row["flags"] |= dispatch.flag_defines()["SHAPE_FLIP_NORMALS"]
