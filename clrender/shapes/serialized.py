"""Mitsuba's ``serialized`` shape: one mesh of a compressed .serialized file (clrender/shapes/serializedfile.py).

```xml
<shape type="serialized">
    <string name="filename" value="meshes/scene.serialized"/>   <!-- required -->
    <integer name="shape_index" value="0"/>                     <!-- which mesh of the file, default 0 -->
    <boolean name="face_normals" value="false"/>                <!-- default false -->
    <boolean name="flip_normals" value="false"/>                <!-- default false -->
    <transform name="to_world"> ... </transform>
    <bsdf type="..."/>  <emitter type="area"> ... </emitter>
</shape>
```
"""
from ..errors import SceneError
from ..scene.registry import register
from .serializedfile import load_serialized
from .trianglemesh import MitsubaMeshOptions, TriangleMesh


@register("shape", "serialized", fmt="mitsuba")
class MitsubaSerializedMesh(MitsubaMeshOptions, TriangleMesh):
    def __init__(self, props, children, spec):
        index = props.get_int("shape_index", 0)
        if index < 0:
            raise SceneError(f"shape_index must be 0 or more, got {index}", props.location("shape_index"))
        self._load_mitsuba(props, children, spec, lambda path, where: load_serialized(path, where, index))
