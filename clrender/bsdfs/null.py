"""Mitsuba 3's null BSDF: no surface at all for the light that meets it (a straight pass-through); an emitting shape
still emits. Blender's Mitsuba exporter puts one on every area light.

```xml
<shape type="rectangle">
    <bsdf type="null"/>                      <!-- no parameters -->
    <emitter type="area"> ... </emitter>
</shape>
```
It is the opacity mask at opacity 0 (kernels/bsdfs/mask.h: every sample passes straight through with weight 1, as
a discrete event, so a light seen through it counts in full; eval and pdf are 0, so no light is sampled from it).
As in Mitsuba's `path`, it still blocks shadow rays, and each pass-through counts as a bounce.
"""
from ..scene.registry import register
from .diffuse import Diffuse
from .mask import Mask


@register("bsdf", "null", fmt="mitsuba")
class NullBsdf(Mask):
    owner = '<bsdf type="null">'
    children = ()

    def __init__(self, props, children, spec):
        self.bsdfs = [Diffuse.default(0.0)]   # never reached at opacity 0; the mask's row needs a child
        self.textures = {}
        self.opacity, self.texture = 0.0, None
