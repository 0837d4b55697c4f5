"""Wavefront OBJ mesh.

```xml
<mesh type="obj">
    <string name="filename" value="meshes/bunny.obj"/>   <!-- required; relative to the XML file -->
    <transform name="toWorld"> ... </transform>          <!-- default: identity -->
    <bsdf type="..."/>                                   <!-- default: diffuse, albedo 0.5 -->
    <emitter type="area"> ... </emitter>                 <!-- optional -->
</mesh>
```
Faces with more than three vertices are fan-triangulated; without `vn` the shading normal is the face normal.
"""
import numpy as np

from ..scene.registry import register
from .objfile import load_obj
from .trianglemesh import MitsubaMeshOptions, TriangleMesh


@register("mesh", "obj")
class ObjMesh(TriangleMesh):
    def __init__(self, props, children, spec):
        self._load(props, children, spec, load_obj)


@register("shape", "obj", fmt="mitsuba")
class MitsubaObjMesh(MitsubaMeshOptions, ObjMesh):
    """Mitsuba 3's OBJ shape.

    ```xml
    <shape type="obj">
        <string name="filename" value="meshes/bunny.obj"/>   <!-- required -->
        <boolean name="face_normals" value="false"/>        <!-- default false -->
        <boolean name="flip_normals" value="false"/>        <!-- default false -->
        <boolean name="flip_tex_coords" value="true"/>      <!-- default true: v -> 1 - v, as Mitsuba -->
        <transform name="to_world"> ... </transform>
        <bsdf type="..."/>  <emitter type="area"> ... </emitter>   <!-- nested or <ref id="..."/> -->
    </shape>
    ```
    """

    def __init__(self, props, children, spec):
        flip_uv = props.get_bool("flip_tex_coords", True)

        def load(path, where):
            mesh = load_obj(path, where)
            if flip_uv and mesh.uvs is not None:
                mesh.uvs = np.column_stack([mesh.uvs[:, 0], 1.0 - mesh.uvs[:, 1]]).astype(np.float32)
            return mesh

        self._load_mitsuba(props, children, spec, load)
