"""Mitsuba 3's opacity mask: the nested BSDF with probability `opacity`, a straight pass-through otherwise.

```xml
<bsdf type="mask">
    <float name="opacity" value="0.4"/>      <!-- in [0, 1], default 0.5; or <texture name="opacity"> -->
    <bsdf type="diffuse"/>
</bsdf>
```
f = opacity f_child plus the transparent part, a delta transmission wo = -wi with weight 1 - opacity (sampled with
probability 1 - opacity: weight 1, MEASURE_DISCRETE, eta 1). eval and pdf hold opacity times the child's non-delta
parts. A texture opacity reads the texture's first channel. Bsdf row (kernels/bsdfs/mask.h): p.mask =
opacity(_tex), child (row offset).
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from ..textures.texture import param
from .composite import Composite


@register("bsdf", "mask", fmt="mitsuba")
class Mask(Composite):
    kernel = "bsdfs/mask.h"
    PARAMS = [("opacity", "texture"), ("child", "int")]
    FLAGS = ("DELTA",)    # the pass-through
    owner = '<bsdf type="mask">'

    def __init__(self, props, children, spec):
        self.read_children(spec, children, (1,), ("opacity",))
        self.texture = self.textures.get("opacity")
        if self.texture is not None and props.has("opacity"):
            raise SceneError("opacity given both as a number and as a texture", props.location("opacity"))
        self.opacity = float(props.get_float("opacity", 0.5))
        if not 0 <= self.opacity <= 1:
            raise SceneError(f"opacity must be within [0, 1], got {self.opacity}", props.location("opacity"))
        if self.texture is not None and self.texture.max_value() > 1:
            raise SceneError("an opacity texture must stay within [0, 1]",
                             getattr(self.texture.spec, "location", None))

    def fill(self, p, row, textures):
        p["child"] = self.child_offsets[0]
        return param(p, "opacity", np.full(3, self.opacity), self.texture, textures)
