"""PLY mesh, binary or ASCII (*extension*: Nori reads only OBJ).

```xml
<mesh type="ply">
    <string name="filename" value="meshes/terrain.ply"/>  <!-- required -->
    <transform name="toWorld"> ... </transform>           <!-- default: identity -->
</mesh>
```
Vertex normals (nx, ny, nz) and texture coordinates are used when the file has them.
"""
from ..scene.registry import register
from .plyfile import load_ply
from .trianglemesh import TriangleMesh


@register("mesh", "ply")
class PlyMesh(TriangleMesh):
    def __init__(self, props, children, spec):
        self._load(props, children, spec, load_ply)
