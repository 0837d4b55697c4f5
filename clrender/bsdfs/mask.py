"""Mitsuba 3's opacity mask: the nested BSDF with probability `opacity`, a straight pass-through otherwise.

```xml
<bsdf type="mask">
    <float name="opacity" value="0.4"/>      <!-- in [0, 1], default 0.5; or <texture name="opacity"> -->
    <bsdf type="diffuse"/>
</bsdf>
```
f = opacity f_child plus the transparent part, a delta transmission wo = -wi with weight 1 - opacity (sampled with
probability 1 - opacity: weight 1, MEASURE_DISCRETE, eta 1). eval and pdf hold opacity times the child's non-delta
parts. A texture opacity is read as Mitsuba reads a float texture
(Texture.float_view: a bitmap's luminance). Bsdf row (kernels/bsdfs/mask.h): p.mask =
opacity(_tex), child (row offset).
"""
from ..scene.registry import register
from ..textures.texture import param
from .composite import Composite


@register("bsdf", "mask", fmt="mitsuba")
class Mask(Composite):
    kernel = "bsdfs/mask.h"
    PARAMS = [("opacity", "float_texture"), ("child", "int")]
    FLAGS = ("DELTA", "TRANSMISSION")    # the pass-through
    # null_transmission: what volpath's shadow rays carry through it (1 - opacity (1 - the child's))
    METHODS = ("eval", "pdf", "sample", "null_transmission")
    owner = '<bsdf type="mask">'

    def __init__(self, props, children, spec):
        self.read_children(spec, children, (1,), ("opacity",))
        self.opacity, self.texture = self.read_fraction(props, "opacity")

    def fill(self, p, row, textures):
        p["child"] = self.child_offsets[0]
        return param(p, "opacity", self.opacity, self.texture, textures)
