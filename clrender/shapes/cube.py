"""Mitsuba 3's ``cube``: the cube [-1, 1]^3 as a mesh of 12 triangles, 4 vertices per face with the face's
normal and uvs (0,1), (1,1), (1,0), (0,0) in the order Mitsuba lists them (checked against Mitsuba 3.9's own
mesh: tests/test_mitsuba_format.py).

```xml
<shape type="cube">
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

# Per face: its normal and its four corners in Mitsuba's order (signs of x, y, z).
_FACES = (
    ((0, -1, 0), ((1, -1, -1), (1, -1, 1), (-1, -1, 1), (-1, -1, -1))),
    ((0, 1, 0), ((1, 1, -1), (-1, 1, -1), (-1, 1, 1), (1, 1, 1))),
    ((1, 0, 0), ((1, -1, -1), (1, 1, -1), (1, 1, 1), (1, -1, 1))),
    ((0, 0, 1), ((1, -1, 1), (1, 1, 1), (-1, 1, 1), (-1, -1, 1))),
    ((-1, 0, 0), ((-1, -1, 1), (-1, 1, 1), (-1, 1, -1), (-1, -1, -1))),
    ((0, 0, -1), ((1, 1, -1), (1, -1, -1), (-1, -1, -1), (-1, 1, -1))),
)
_UVS = ((0, 1), (1, 1), (1, 0), (0, 0))


def cube_mesh() -> MeshData:
    positions = np.array([c for _, corners in _FACES for c in corners], np.float64)
    normals = np.repeat(np.array([n for n, _ in _FACES], np.float64), 4, axis=0)
    uvs = np.tile(np.array(_UVS, np.float64), (6, 1))
    base = 4 * np.arange(6)[:, None]
    faces = np.concatenate([base + [0, 1, 2], base + [3, 0, 2]], axis=1).reshape(-1, 3)
    return MeshData(positions=positions, normals=normals, uvs=uvs, faces=faces)


@register("shape", "cube", fmt="mitsuba")
class MitsubaCube(MitsubaMeshOptions, TriangleMesh):
    def __init__(self, props, children, spec):
        self._load_generated(props, children, spec, cube_mesh, "cube")
