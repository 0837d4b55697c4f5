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


@register("scene", "scene", fmt="mitsuba")
class MitsubaScene(Scene):
    """The root of a Mitsuba 3 file: shapes, scene-level emitters, one sensor (holding film and sampler), one
    integrator; objects declared at the top level only to be referenced (bsdfs, textures) are allowed.

    ```xml
    <scene version="3.0.0">
        <integrator type="path"/>                 <!-- default: path (unbounded depth) -->
        <sensor type="perspective">               <!-- default: Mitsuba's (below) -->
            <film type="hdrfilm"/>                <!-- default 768 x 576, gaussian filter -->
            <sampler type="independent"/>         <!-- default 4 samples per pixel -->
        </sensor>
        <bsdf type="diffuse" id="white"/>         <!-- declared for <ref id="white"/> -->
        <shape type="obj"> ... </shape>           <!-- any number -->
        <emitter type="constant"/>                <!-- any number (area emitters live in a shape) -->
    </scene>
    ```
    A scene without a sensor is an error, as in Mitsuba 3.9 (which loads it but cannot render it); without an
    integrator it is rendered by path tracing with unbounded depth (Mitsuba 3.9 asks for one; earlier 3.x
    versions made this same default).
    """
    children = ("shape", "emitter", "sensor", "integrator", "bsdf", "texture")

    def __init__(self, props, children, spec):
        self.location = spec.location
        self.nori_dialect = "upstream"   # Mitsuba's camera convention is upstream Nori's
        self.shapes, self.emitters = [], []
        self.camera = self.integrator = None
        for c in children:
            tag = c.spec.tag
            if tag == "shape":
                self.shapes.append(c)
            elif tag == "emitter":
                if getattr(c, "is_area", False):
                    raise SceneError("an area emitter must be nested in a <shape>", c.spec.location)
                self.emitters.append(c)
            elif tag in ("sensor", "integrator"):
                slot = "camera" if tag == "sensor" else tag
                if getattr(self, slot) is not None:
                    raise SceneError(f"clrender renders one <{tag}> per scene; this is a second one",
                                     c.spec.location)
                setattr(self, slot, c)
            # bsdfs and textures at the top level are only declared for references
        if self.camera is None:
            raise SceneError('no sensor was specified: add e.g. <sensor type="perspective"> with a <film '
                             'type="hdrfilm"> (Mitsuba 3 cannot render a scene without one either)', spec.location)
        if self.integrator is None:
            self.integrator = _default_integrator(spec)
        self.sampler = self.camera.sampler


def _default_integrator(spec):
    """Mitsuba's default integrator is ``path`` with unbounded depth; where no Mitsuba ``path`` plugin is
    registered, clrender's unbounded ``path_mis`` converges to the same image (only Russian roulette differs)."""
    from .registry import instantiate, registered

    if "path" in registered("integrator", "mitsuba"):
        return instantiate("integrator", "path", {}, spec.location, fmt="mitsuba")
    return instantiate("integrator", "path_mis", {}, spec.location)
