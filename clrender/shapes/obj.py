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
from ..scene.registry import register
from .objfile import load_obj
from .trianglemesh import TriangleMesh


@register("mesh", "obj")
class ObjMesh(TriangleMesh):
    def __init__(self, props, children, spec):
        self._load(props, children, spec, load_obj)
