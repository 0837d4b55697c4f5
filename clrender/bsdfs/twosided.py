"""Mitsuba 3's two-sided adapter: the nested BSDF on both sides of the surface, or a second one on the back.

```xml
<bsdf type="twosided">
    <bsdf type="diffuse"/>            <!-- front (and back, when it is the only one) -->
    <bsdf type="plastic"/>            <!-- optional: the back side -->
</bsdf>
```
On the back (cos theta_i < 0) the child is queried in the mirrored frame (z flipped for wi and wo). The children
must reflect only: a child whose flags say TRANSMISSION (a dielectric, a mask or null, principledthin, principled
with spec_trans, or a composite holding one) is an error, as in Mitsuba. Bsdf row (kernels/bsdfs/twosided.h):
p.twosided = front, back (row offsets of the children).
"""
from ..errors import SceneError
from ..scene.registry import register
from .composite import Composite


def _descendants(bsdfs):
    for c in bsdfs:
        yield c
        yield from _descendants(getattr(c, "bsdfs", ()))


@register("bsdf", "twosided", fmt="mitsuba")
class TwoSided(Composite):
    kernel = "bsdfs/twosided.h"
    PARAMS = [("front", "int"), ("back", "int")]
    owner = '<bsdf type="twosided">'

    def __init__(self, props, children, spec):
        self.read_children(spec, children, (1, 2))
        for c in _descendants(self.bsdfs):
            cspec = getattr(c, "spec", None)
            if "TRANSMISSION" in c.own_capabilities():   # (the one that transmits, not a composite holding it)
                kind = getattr(cspec, "type", type(c).__name__)
                raise SceneError(f"{self.owner}: the nested <bsdf type=\"{kind}\"> transmits light; "
                                 f"twosided takes reflecting BSDFs only (as in Mitsuba)",
                                 getattr(cspec, "location", None))

    def fill(self, p, row, textures):
        p["front"] = self.child_offsets[0]
        p["back"] = self.child_offsets[-1]
        return False
