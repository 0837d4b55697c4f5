"""The root `<scene>`: shapes, scene-level emitters, one camera, one integrator, an optional sampler.

```xml
<scene>
    <integrator type="path_mis"/>           <!-- required -->
    <sampler type="independent">             <!-- default: independent, 1 sample per pixel -->
        <integer name="sampleCount" value="64"/>
    </sampler>
    <camera type="perspective"> ... </camera>   <!-- required -->
    <mesh type="obj"> ... </mesh>               <!-- any number -->
    <emitter type="point"> ... </emitter>       <!-- any number (not area: those live in a mesh) -->
</scene>
```
"""
from __future__ import annotations

from ..errors import SceneError
from .registry import register


@register("scene", "scene")
class Scene:
    children = ("mesh", "emitter", "camera", "integrator", "sampler")

    def __init__(self, props, children, spec):
        self.location = spec.location
        self.nori_dialect = spec.dialect
        self.shapes = []
        self.emitters = []
        self.camera = self.integrator = self.sampler = None
        for c in children:
            tag = c.spec.tag
            if tag == "mesh":
                self.shapes.append(c)
            elif tag == "emitter":
                if getattr(c, "is_area", False):
                    raise SceneError("an area emitter must be nested in a <mesh>", c.spec.location)
                self.emitters.append(c)
            else:
                if getattr(self, tag) is not None:
                    raise SceneError(f"a scene can have only one <{tag}>", c.spec.location)
                setattr(self, tag, c)
        if self.camera is None:
            raise SceneError("no camera was specified: add a <camera type=\"perspective\">", spec.location)
        if self.integrator is None:
            raise SceneError("no integrator was specified: add e.g. <integrator type=\"normals\"/>",
                             spec.location)

    @property
    def sample_count(self) -> int:
        return self.sampler.sample_count if self.sampler is not None else 1

    @property
    def width(self) -> int:
        return self.camera.width

    @property
    def height(self) -> int:
        return self.camera.height
