"""Mitsuba 3's ``cylinder``: radius ``radius`` about the axis from ``p0`` to ``p1``, open ends, normals outward,
uv = (phi / 2pi, z along the axis in [0, 1]), phi measured in the axis's frame (the Duff et al. orthonormal basis,
as Mitsuba builds it) (checked against Mitsuba 3.9's own intersections: tests/test_mitsuba_shapes.py).

```xml
<shape type="cylinder">
    <point name="p0" value="0, 0, 0"/>            <!-- default 0, 0, 0 -->
    <point name="p1" value="0, 0, 1"/>            <!-- default 0, 0, 1 -->
    <float name="radius" value="1"/>              <!-- default 1 -->
    <transform name="to_world"> ... </transform>   <!-- default identity -->
    <boolean name="flip_normals" value="false"/>   <!-- default false -->
    <bsdf type="..."/>  <emitter type="area"> ... </emitter>
</shape>
```
Our BVH knows triangles and spheres, so the cylinder is ``SEGMENTS`` quads around with exact vertex normals: its
surface lies within 1 - cos(pi / SEGMENTS) = 1.9e-5 of the radius, far below what an image shows.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .meshdata import MeshData
from .trianglemesh import MitsubaMeshOptions, TriangleMesh

#: quads around the cylinder
SEGMENTS = 512


def axis_frame(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing the unit vector d to a right-handed basis (Duff et al. 2017)."""
    sign = 1.0 if d[2] >= 0 else -1.0
    a = -1.0 / (sign + d[2])
    b = d[0] * d[1] * a
    return (np.array([1 + sign * d[0] * d[0] * a, sign * b, -sign * d[0]]),
            np.array([b, sign + d[1] * d[1] * a, -d[1]]))


def cylinder_mesh(p0=(0, 0, 0), p1=(0, 0, 1), radius=1.0, n: int = SEGMENTS) -> MeshData:
    p0, p1 = np.asarray(p0, np.float64), np.asarray(p1, np.float64)
    axis = p1 - p0
    length = np.linalg.norm(axis)
    s, t = axis_frame(axis / length)
    phi = np.arange(n + 1) * (2 * np.pi / n)     # the seam's vertices twice: u wraps 1 -> 0 there
    ring = np.cos(phi)[:, None] * s + np.sin(phi)[:, None] * t
    k = len(phi)
    positions = np.concatenate([p0 + radius * ring, p1 + radius * ring])
    u = phi / (2 * np.pi)
    uv = np.concatenate([np.c_[u, np.zeros(k)], np.c_[u, np.ones(k)]])
    i = np.arange(n)
    faces = np.concatenate([np.stack([i, i + 1, k + i + 1], axis=1), np.stack([i, k + i + 1, k + i], axis=1)])
    return MeshData(positions, np.concatenate([ring, ring]), uv, faces)


@register("shape", "cylinder", fmt="mitsuba")
class MitsubaCylinder(MitsubaMeshOptions, TriangleMesh):
    def __init__(self, props, children, spec):
        p0 = np.asarray(props.get_point("p0", [0.0, 0.0, 0.0]), np.float64)
        p1 = np.asarray(props.get_point("p1", [0.0, 0.0, 1.0]), np.float64)
        radius = float(props.get_float("radius", 1.0))
        if not (np.isfinite(radius) and radius > 0):
            raise SceneError(f"cylinder radius must be a positive number, got {radius}", props.location("radius"))
        if not (np.all(np.isfinite(p0)) and np.all(np.isfinite(p1)) and np.linalg.norm(p1 - p0) > 0):
            raise SceneError(f"cylinder p0 and p1 must be distinct finite points, got {p0.tolist()}, {p1.tolist()}",
                             spec.location)
        self._load_generated(props, children, spec, lambda: cylinder_mesh(p0, p1, radius), "cylinder")
