"""Mitsuba 3's blend of two BSDFs: f = (1 - weight) f_first + weight f_second.

```xml
<bsdf type="blendbsdf">
    <float name="weight" value="0.3"/>       <!-- in [0, 1], default 0.5; or <texture name="weight"> -->
    <bsdf type="conductor"/>                 <!-- weight 0 -->
    <bsdf type="diffuse"/>                   <!-- weight 1 -->
</bsdf>
```
Sampling picks a child with its blend weight. A delta sample keeps the chosen child's weight (MEASURE_DISCRETE);
a non-delta sample is weighted by the mixture: (1-w) f1 + w f2 over (1-w) pdf1 + w pdf2 (eval and pdf hold the
non-delta parts only). A texture weight is read as Mitsuba reads a float texture
(Texture.float_view: a bitmap's luminance). Bsdf row
(kernels/bsdfs/blendbsdf.h): p.blendbsdf = weight(_tex), first, second (row offsets of the children).
"""
from ..scene.registry import register
from ..textures.texture import param
from .composite import Composite


@register("bsdf", "blendbsdf", fmt="mitsuba")
class BlendBsdf(Composite):
    kernel = "bsdfs/blendbsdf.h"
    PARAMS = [("weight", "float_texture"), ("first", "int"), ("second", "int")]
    # null_transmission: the children's, blended (what volpath's shadow rays carry through it, as Mitsuba's)
    METHODS = ("eval", "pdf", "sample", "null_transmission")
    owner = '<bsdf type="blendbsdf">'

    def __init__(self, props, children, spec):
        self.read_children(spec, children, (2,), ("weight",))
        self.weight, self.texture = self.read_fraction(props, "weight")

    def fill(self, p, row, textures):
        p["first"], p["second"] = self.child_offsets
        return param(p, "weight", self.weight, self.texture, textures)
