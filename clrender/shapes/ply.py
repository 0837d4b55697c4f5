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
from .trianglemesh import MitsubaMeshOptions, TriangleMesh


@register("mesh", "ply")
class PlyMesh(TriangleMesh):
    def __init__(self, props, children, spec):
        self._load(props, children, spec, load_ply)


@register("shape", "ply", fmt="mitsuba")
class MitsubaPlyMesh(MitsubaMeshOptions, PlyMesh):
    """Mitsuba 3's PLY shape.

    ```xml
    <shape type="ply">
        <string name="filename" value="meshes/terrain.ply"/>  <!-- required -->
        <boolean name="face_normals" value="false"/>         <!-- default false -->
        <boolean name="flip_normals" value="false"/>         <!-- default false -->
        <transform name="to_world"> ... </transform>
        <bsdf type="..."/>  <emitter type="area"> ... </emitter>
    </shape>
    ```
    """

    def __init__(self, props, children, spec):
        self._load_mitsuba(props, children, spec, load_ply)
