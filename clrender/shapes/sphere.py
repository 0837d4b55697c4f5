"""Analytic sphere (the ETH variant of Nori), intersected exactly in the kernel.

```xml
<mesh type="sphere">
    <point name="center" value="0, 0, 0"/>   <!-- default 0,0,0 -->
    <float name="radius" value="1"/>         <!-- default 1 -->
</mesh>
```
Normals point outward; uv = (atan2(n.y, n.x) / 2pi wrapped to [0,1), acos(n.z) / pi), n in the sphere's own frame.
The Nori dialect `eth2023` (clrender/scene/dialect.py) turns that frame half a revolution about z, so there
u = 1/2 + atan2(n.y, n.x) / 2pi (wrapped): the uv the ETH course's test files up to 2023 were made with.
Tables (kernels/shapes/sphere.h): one row of `spheres` (centre, radius) and of `sphere_shape` (this shape); the
row's first is that row. Row: p.sphere.rot = the rotation taking the sphere's own frame to the world, a unit
quaternion (x, y, z, w) with w >= 0, whose w has its sign bit set where the frame is mirrored (to_world with a
negative determinant). An emitting sphere is sampled analytically (the cone it subtends), so it has no CDF.
"""
import numpy as np

from ..device import dispatch
from ..errors import SceneError
from ..scene.dialect import sphere_u_turn
from ..scene.registry import register
from .shape import SPHERE_EXTENT_MAX, Shape


def frame_quaternion(m: np.ndarray) -> np.ndarray:
    """The row p.sphere.rot of an orthogonal 3 x 3 matrix (see the module's docstring): its rotation, or for a
    mirror (det < 0) the rotation -m, as (x, y, z, w), w >= 0, with w's sign bit set for a mirror."""
    mirror = np.linalg.det(m) < 0
    r = -m if mirror else m
    # Shepperd's method: start from the largest of the four squared components (stable for every rotation)
    t = np.trace(r)
    d = [t, r[0, 0], r[1, 1], r[2, 2]]
    k = int(np.argmax(d))
    if k == 0:
        w = np.sqrt(1.0 + t) / 2
        q = np.array([(r[2, 1] - r[1, 2]) / (4 * w), (r[0, 2] - r[2, 0]) / (4 * w), (r[1, 0] - r[0, 1]) / (4 * w), w])
    else:
        i, j, l = (k - 1, k % 3, (k + 1) % 3)
        v = np.zeros(3)
        v[i] = np.sqrt(max(1.0 + 2 * r[i, i] - t, 0.0)) / 2
        v[j] = (r[j, i] + r[i, j]) / (4 * v[i])
        v[l] = (r[l, i] + r[i, l]) / (4 * v[i])
        q = np.array([*v, (r[l, j] - r[j, l]) / (4 * v[i])])
    q = q / np.linalg.norm(q)
    if q[3] < 0:
        q = -q
    q = q.astype(np.float32)
    q[3] = abs(q[3])
    if mirror:
        q[3] = -q[3] if q[3] != 0 else np.float32(-0.0)
    return q


@register("mesh", "sphere")
class Sphere(Shape):
    kernel = "shapes/sphere.h"
    PARAMS = [("rot", "float4")]
    frame = np.eye(3)   # the sphere's own axes in the world (Mitsuba's to_world rotation)

    def __init__(self, props, children, spec):
        self.center = np.asarray(props.get_point("center", np.zeros(3)), np.float64)
        self.radius = float(props.get_float("radius", 1.0))
        if not np.all(np.isfinite(self.center)):
            raise SceneError(f"sphere center must be finite, got {self.center}", props.location("center"))
        if not (self.radius > 0 and np.isfinite(self.radius)):
            raise SceneError(f"sphere radius must be a positive number, got {self.radius}", spec.location)
        turn = 2.0 * np.pi * sphere_u_turn(spec.dialect)
        if turn:   # u shifted by turning the sphere's own frame: uv, dp/du and shading frame stay consistent
            c, s = np.round([np.cos(turn), np.sin(turn)], 12)   # a half turn exactly diag(-1, -1, 1)
            self.frame = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
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
        row[dispatch.member_of(type(self))]["rot"] = frame_quaternion(self.frame)

    def area_distribution(self):
        return None, self.area()


@register("shape", "sphere", fmt="mitsuba")
class MitsubaSphere(Sphere):
    """Mitsuba 3's analytic ``sphere``: the sphere of ``radius`` about ``center``, then ``to_world`` (which may
    rotate, translate and scale uniformly; Mitsuba forbids non-uniform scales and shears, and so do we).
    uv = (phi / 2pi, theta / pi) as above in the sphere's own frame, which to_world turns (the same as Mitsuba's).

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
        self.frame = lin / float(scales.mean())
        if np.linalg.det(lin) < 0:      # a mirror turns Mitsuba's sphere inside out (checked against Mitsuba 3.9.1)
            self.flip_normals = not self.flip_normals
        self._check_extent(spec)
        self._attach(children, spec)

    def fill(self, ctx, index, row):
        super().fill(ctx, index, row)
        if self.flip_normals:
            row["flags"] |= dispatch.flag_defines()["SHAPE_FLIP_NORMALS"]
