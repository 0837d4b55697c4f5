"""Mitsuba 3's ``disk``: the unit disk in the xy plane, normal +z, uv = (r, phi / 2pi) with phi = atan2(y, x) in
[0, 2pi) (checked against Mitsuba 3.9's own intersections: tests/test_mitsuba_shapes.py).

```xml
<shape type="disk">
    <transform name="to_world"> ... </transform>   <!-- default identity -->
    <boolean name="flip_normals" value="false"/>   <!-- default false -->
    <bsdf type="..."/>  <emitter type="area"> ... </emitter>
</shape>
```
Our BVH knows triangles and spheres, so the disk is a fan of ``SEGMENTS`` triangles: its rim lies within
1 - cos(pi / SEGMENTS) = 1.9e-5 of the radius (area 2.5e-5 short), far below what an image shows. Each triangle
has its own centre vertex whose phi is the triangle's middle angle, so v interpolates within each sector.
"""
import numpy as np

from ..scene.registry import register
from .meshdata import MeshData
from .trianglemesh import MitsubaMeshOptions, TriangleMesh

#: triangles around the disk
SEGMENTS = 512


def disk_mesh(n: int = SEGMENTS) -> MeshData:
    phi = np.arange(n + 1) * (2 * np.pi / n)     # the seam's vertex twice: v wraps 1 -> 0 there
    rim = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=1)
    mid = (phi[:-1] + phi[1:]) / 2
    p = np.concatenate([rim, np.zeros((n, 3))])
    uv = np.concatenate([np.stack([np.ones_like(phi), phi / (2 * np.pi)], axis=1),
                         np.stack([np.zeros(n), mid / (2 * np.pi)], axis=1)])
    i = np.arange(n)
    faces = np.stack([n + 1 + i, i, i + 1], axis=1)     # counter-clockwise seen from +z
    return MeshData(p, np.tile([0.0, 0.0, 1.0], (len(p), 1)), uv, faces)


@register("shape", "disk", fmt="mitsuba")
class MitsubaDisk(MitsubaMeshOptions, TriangleMesh):
    def __init__(self, props, children, spec):
        self._load_generated(props, children, spec, disk_mesh, "disk")
