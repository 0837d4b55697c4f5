"""Mitsuba 3's `aov`: a geometric quantity of the surface each camera ray sees, instead of radiance.

```xml
<integrator type="aov">
    <string name="aovs" value="dd.y:depth"/>   <!-- required: one <name>:<type> pair -->
</integrator>
```
Types: `depth` (distance along the ray from the near clip plane, where Mitsuba's camera rays start: Mitsuba's
value, not quite the distance from the pinhole; written to all three channels), `position` (world
x, y, z), `geo_normal` and `sh_normal` (the geometric and the shading normal, signed, as Mitsuba writes them);
0 where the ray escapes. Our film holds one RGB image, so one AOV only: a list of several, a nested integrator
(whose image Mitsuba writes beside the AOVs) or Mitsuba's other types (albedo, uv, dp_du, ...) are errors.
Kernel: kernels/integrators/aov.h.
"""
from ..errors import SceneError
from ..scene.registry import register
from .integrator import Integrator

KINDS = {"depth": 0, "position": 1, "geo_normal": 2, "sh_normal": 3}
MITSUBA_ONLY = ("albedo", "uv", "dp_du", "dp_dv", "duv_dx", "duv_dy", "prim_index", "shape_index")


@register("integrator", "aov", fmt="mitsuba")
class Aov(Integrator):
    kernel = "aov"
    PARAMS = [("kind", "uint")]
    children = ("integrator",)   # accepted so that the error below can say why it is not supported

    def __init__(self, props, children, spec):
        where = '<integrator type="aov">'
        if children:
            raise SceneError(f"{where}: a nested integrator is not supported: our film holds one RGB image, so "
                             "the aov integrator renders one AOV and nothing beside it", spec.location)
        text = props.get_string("aovs")
        loc = props.location("aovs")
        items = [t.strip() for t in text.split(",") if t.strip()]
        if not items:
            raise SceneError(f"{where}: aovs is empty; give one <name>:<type> pair, type one of "
                             f"{', '.join(KINDS)}", loc)
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
