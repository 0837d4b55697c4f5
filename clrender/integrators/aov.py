"""Mitsuba 3's `aov`: a geometric quantity of the surface each camera ray sees, instead of radiance.

```xml
<integrator type="aov">
    <string name="aovs" value="dd.y:depth"/>   <!-- required: one <name>:<type> pair -->
</integrator>
```
Types: `depth` (distance along the ray from the near clip plane, where Mitsuba's camera rays start: Mitsuba's
value, not quite the distance from the pinhole; written to all three channels), `position` (world
x, y, z), `geo_normal` and `sh_normal` (the geometric and the shading normal, signed, as Mitsuba writes them);
0 where the ray escapes. Our film holds one RGB image, so one AOV only: a list of several or Mitsuba's other types
(albedo, uv, dp_du, ...) are errors. With a nested integrator Mitsuba's image is the nested integrator's, and the
AOVs are channels beside it:

```xml
<integrator type="aov">
    <string name="aovs" value="nn:sh_normal, dd.y:depth"/>   <!-- any of Mitsuba's types -->
    <integrator type="path" name="image"/>
</integrator>
```
clrender then renders the nested integrator as the image (Mitsuba's R, G, B) and, with `clrender render`, each AOV
of the four types above by a pass of its own (same samples per pixel and seed), written beside it under Mitsuba
3.9.1's channel names: `<name>.T` for depth, `<name>.X/.Y/.Z` for the others; Mitsuba's other types are left out
with a warning (renderer.aov_channels). Mitsuba also writes the nested integrator's own channels, `<its name>.R/G/B`
(the image again) and `.A` (the fraction of its rays that hit something): those are not written. Kernel:
kernels/integrators/aov.h.
"""
import logging

from ..errors import SceneError
from ..scene.registry import register
from .integrator import Integrator

log = logging.getLogger("clrender")

KINDS = {"depth": 0, "position": 1, "geo_normal": 2, "sh_normal": 3}
MITSUBA_ONLY = ("albedo", "uv", "dp_du", "dp_dv", "duv_dx", "duv_dy", "prim_index", "shape_index")


@register("integrator", "aov", fmt="mitsuba")
class Aov(Integrator):
    kernel = "aov"
    PARAMS = [("kind", "uint")]
    children = ("integrator",)
    nested = None

    def __init__(self, props, children, spec):
        where = '<integrator type="aov">'
        #: the nested integrator that renders the image (MitsubaScene renders it in this one's place), or None
        self.nested = children[0] if children else None
        if len(children) > 1:
            raise SceneError(f"{where} takes one nested integrator, got {len(children)}", children[1].spec.location)
        text = props.get_string("aovs")
        loc = props.location("aovs")
        items = [t.strip() for t in text.split(",") if t.strip()]
        if not items:
            raise SceneError(f"{where}: aovs is empty; give one <name>:<type> pair, type one of "
                             f"{', '.join(KINDS)}", loc)
        if self.nested is not None:   # channels beside the nested integrator's image, each a pass of its own
            #: the (name, type) pairs as written
            self.items = []
            for item in items:
                name, sep, kind = item.partition(":")
                if not sep or not name.strip() or kind.strip() not in (*KINDS, *MITSUBA_ONLY):
                    raise SceneError(f"{where}: {item!r} is not a <name>:<type> pair with type one of "
                                     f"{', '.join((*KINDS, *MITSUBA_ONLY))}", loc)
                self.items.append((name.strip(), kind.strip()))
            self.aovs, self.location = text, spec.location
            return
        if len(items) > 1:
            raise SceneError(f"{where}: aovs lists {len(items)} AOVs ({text!r}) but our film holds one RGB image: "
                             f"give one <name>:<type> pair (render again for the others)", loc)
        name, sep, kind = items[0].partition(":")
        if not sep or not name.strip() or not kind.strip():
            raise SceneError(f"{where}: {items[0]!r} is not a <name>:<type> pair (e.g. \"dd.y:depth\")", loc)
        kind = kind.strip()
        if kind not in KINDS:
            what = "is a Mitsuba AOV type clrender does not render" if kind in MITSUBA_ONLY else "is not an AOV type"
            raise SceneError(f"{where}: {kind!r} {what}; supported: {', '.join(KINDS)}", loc)
        self.name, self.kind = name.strip(), kind

    def fill(self, p):
        p["kind"] = KINDS[self.kind]

    def channels(self, rfilter) -> None:
        """With a nested integrator (which renders the image): no second-moment channels (see ``renderable``)."""
        return None

    def renderable(self) -> list[tuple[str, str]]:
        """The (name, type) AOVs that a pass of this integrator can render; the others are named in a warning."""
        skipped = [f"{n}:{k}" for n, k in self.items if k not in KINDS]
        if skipped:
            log.warning("%s: <integrator type=\"aov\">: clrender does not render the AOVs %s (it renders %s); "
                        "they are left out", self.location, ", ".join(skipped), ", ".join(KINDS))
        return [(n, k) for n, k in self.items if k in KINDS]


@register("integrator", "depth", fmt="mitsuba")
class Depth(Aov):
    """Mitsuba 3's `depth`: the distance to what each camera ray sees, in every channel; Mitsuba 3.9.1 renders the
    same image as `aov` with `dd.y:depth` (checked side by side), and so does this.

    ```xml
    <integrator type="depth"/>
    ```
    """
    children = ()

    def __init__(self, props, children, spec):
        self.name, self.kind = "depth", "depth"
