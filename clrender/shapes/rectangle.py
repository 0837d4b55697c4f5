"""Mitsuba 3's ``rectangle``: [-1, 1]^2 in the xy plane, normal +z, uv = ((x + 1) / 2, (y + 1) / 2) (checked
against Mitsuba 3.9's own intersections: tests/test_mitsuba_shapes.py). Two triangles: exactly the same surface.

```xml
<shape type="rectangle">
    <transform name="to_world"> ... </transform>   <!-- default identity -->
    <boolean name="flip_normals" value="false"/>   <!-- default false -->
    <bsdf type="..."/>  <emitter type="area"> ... </emitter>
</shape>
```
"""
import numpy as np

from ..scene.registry import register
from .meshdata import MeshData
from .trianglemesh import MitsubaMeshOptions, TriangleMesh


def rectangle_mesh() -> MeshData:
    p = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float64)
    normals = np.tile([0.0, 0.0, 1.0], (4, 1))
    return MeshData(p, normals, (p[:, :2] + 1) / 2, np.array([[0, 1, 2], [0, 2, 3]]))


@register("shape", "rectangle", fmt="mitsuba")
class MitsubaRectangle(MitsubaMeshOptions, TriangleMesh):
    def __init__(self, props, children, spec):
        self._load_generated(props, children, spec, rectangle_mesh, "rectangle")
