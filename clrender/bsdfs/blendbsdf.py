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
non-delta parts only). A texture weight reads the texture's first channel. Bsdf row
(kernels/bsdfs/blendbsdf.h): p.blendbsdf = weight(_tex), first, second (row offsets of the children).
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from ..textures.texture import param
from .composite import Composite


@register("bsdf", "blendbsdf", fmt="mitsuba")
class BlendBsdf(Composite):
    kernel = "bsdfs/blendbsdf.h"
    PARAMS = [("weight", "texture"), ("first", "int"), ("second", "int")]
    owner = '<bsdf type="blendbsdf">'

    def __init__(self, props, children, spec):
        self.read_children(spec, children, (2,), ("weight",))
        self.texture = self.textures.get("weight")
        if self.texture is not None and props.has("weight"):
            raise SceneError("weight given both as a number and as a texture", props.location("weight"))
        self.weight = float(props.get_float("weight", 0.5))
        if not 0 <= self.weight <= 1:
            raise SceneError(f"weight must be within [0, 1], got {self.weight}", props.location("weight"))
        if self.texture is not None and self.texture.max_value() > 1:
            raise SceneError("a weight texture must stay within [0, 1]", getattr(self.texture.spec, "location", None))

    def fill(self, p, row, textures):
        p["first"], p["second"] = self.child_offsets
        return param(p, "weight", np.full(3, self.weight), self.texture, textures)
