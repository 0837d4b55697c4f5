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

import logging

from ..errors import SceneError
from .registry import register

log = logging.getLogger("clrender")


@register("scene", "scene")
class Scene:
    children = ("mesh", "emitter", "camera", "integrator", "sampler")

    def __init__(self, props, children, spec):
        self.location = spec.location
        self.nori_dialect = spec.dialect
        self.camera = self.integrator = self.sampler = None
        self._take_children(children, "mesh", {"camera": "camera", "integrator": "integrator", "sampler": "sampler"},
                            "a scene can have only one <{tag}>")
        if self.camera is None:
            raise SceneError("no camera was specified: add a <camera type=\"perspective\">", spec.location)
        if self.integrator is None:
            raise SceneError("no integrator was specified: add e.g. <integrator type=\"normals\"/>",
                             spec.location)

    def _take_children(self, children, shape_tag: str, slots: dict, twice: str) -> None:
        """Shapes (`shape_tag`) and scene-level emitters into lists, each single object into its attribute
        (slots: tag -> attribute; a second one is the error `twice`); other children are passed over."""
        self.shapes, self.emitters = [], []
        for c in children:
            tag = c.spec.tag
            if tag == shape_tag:
                self.shapes.append(c)
            elif tag == "emitter":
                if getattr(c, "is_area", False):
                    raise SceneError(f"an area emitter must be nested in a <{shape_tag}>", c.spec.location)
                self.emitters.append(c)
            elif tag in slots:
                if getattr(self, slots[tag]) is not None:
                    raise SceneError(twice.format(tag=tag), c.spec.location)
                setattr(self, slots[tag], c)

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
    """The root of a Mitsuba 3 file: shapes, scene-level emitters, sensors (each holding film and sampler), one
    integrator; objects declared at the top level only to be referenced (bsdfs, textures, samplers, films, rfilters)
    are allowed. Of several sensors (a multi-view file for inverse rendering) the first is rendered, as Mitsuba's
    `render()` renders sensor 0 unless given another; a warning says so (``cameras`` holds them all).

    ```xml
    <scene version="3.0.0">
        <integrator type="path"/>                 <!-- default: path (unbounded depth) -->
        <sensor type="perspective">               <!-- default: Mitsuba's (below) -->
            <film type="hdrfilm"/>                <!-- default 768 x 576, gaussian filter -->
            <sampler type="independent"/>         <!-- default 4 samples per pixel -->
        </sensor>
        <bsdf type="diffuse" id="white"/>         <!-- declared for <ref id="white"/>; also textures, and a
                                                       sampler, film or rfilter for a sensor's <ref> -->
        <shape type="obj"> ... </shape>           <!-- any number; shapegroup + instance: shapes/instance.py -->
        <emitter type="constant"/>                <!-- any number (area emitters live in a shape) -->
    </scene>
    ```
    A scene without a sensor is an error, as in Mitsuba 3.9 (which loads it but cannot render it); without an
    integrator it is rendered by path tracing with unbounded depth (Mitsuba 3.9 asks for one; earlier 3.x
    versions made this same default).
    """
    children = ("shape", "emitter", "sensor", "integrator", "bsdf", "texture", "sampler", "film", "rfilter", "medium",
                "volume")

    def __init__(self, props, children, spec):
        self.location = spec.location
        self.nori_dialect = "upstream"   # Mitsuba's camera convention is upstream Nori's
        self.camera = self.integrator = None
        # bsdfs, textures, media, volumes, samplers, films and rfilters at the top level are only declared for references
        # (Mitsuba's docs scenes declare <sampler id> beside an included sensor that refers to it; one that nothing
        # refers to is ignored, as Mitsuba 3.9.1 ignores it): _take_children passes them over.
        # So is an area emitter that a shape holds by a <ref> (Mitsuba's own Cornell boxes declare the light at the
        # top level, after the shape): Mitsuba 3.9.1's scene lists area emitters only through their shapes. One that
        # no shape holds stays an error (Mitsuba ignores it silently: the light the file meant is missing).
        attached = {id(c.emitter) for c in children if c.spec.tag == "shape" and getattr(c, "emitter", None)}
        children = [c for c in children if id(c) not in attached]
        #: every sensor, in file order; the first is the one rendered
        self.cameras = [c for c in children if c.spec.tag == "sensor"]
        if len(self.cameras) > 1:
            log.warning("%s: the scene has %d sensors: clrender renders this first one, as Mitsuba's render() does "
                        "unless told another (the others, from %s on, are not rendered)", self.cameras[0].spec.location,
                        len(self.cameras), self.cameras[1].spec.location)
        children = [c for c in children if c.spec.tag != "sensor"]
        self.camera = self.cameras[0] if self.cameras else None
        self._take_children(children, "shape", {"integrator": "integrator"},
                            "clrender renders one <{tag}> per scene; this is a second one")
        from ..shapes.instance import flatten

        self.shapes = flatten(self.shapes)   # shapegroups are declarations; instances become their copies
        if self.camera is None:
            raise SceneError('no sensor was specified: add e.g. <sensor type="perspective"> with a <film '
                             'type="hdrfilm"> (Mitsuba 3 cannot render a scene without one either)', spec.location)
        if self.integrator is None:
            self.integrator = _default_integrator(spec)
        #: the EXR's second-moment channels' prefix (a `moment` integrator's; integrators/moment.py), or None
        self.moment_channels = None
        nested = getattr(self.integrator, "nested", None)
        #: the (name, type) AOVs an `aov` with a nested integrator asks for beside the image (renderer.aov_channels)
        self.aovs = []
        if nested is not None:   # `moment`, `aov` with a nested integrator: that one renders the image
            self.moment_channels = self.integrator.channels(self.camera.filter)
            self.aovs = self.integrator.renderable() if hasattr(self.integrator, "renderable") else []
            self.integrator = nested
        self.sampler = self.camera.sampler


def _default_integrator(spec):
    """Mitsuba's default integrator is ``path`` with unbounded depth; where no Mitsuba ``path`` plugin is
    registered, clrender's unbounded ``path_mis`` converges to the same image (only Russian roulette differs)."""
    from .registry import instantiate, registered

    if "path" in registered("integrator", "mitsuba"):
        return instantiate("integrator", "path", {}, spec.location, fmt="mitsuba")
    return instantiate("integrator", "path_mis", {}, spec.location)
