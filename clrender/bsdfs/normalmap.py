"""Mitsuba 3's normal map adapter: the nested BSDF in the shading frame tilted to the normal a texture gives.

```xml
<bsdf type="normalmap">
    <texture type="bitmap" name="normalmap">             <!-- or <rgb name="normalmap" value="..."/> -->
        <string name="filename" value="normals.png"/>
        <boolean name="raw" value="true"/>                <!-- the usual: the pixels are vectors, not colours -->
    </texture>
    <boolean name="flip_invalid_normals" value="true"/>   <!-- default true -->
    <boolean name="use_shadowing_function" value="true"/> <!-- default true -->
    <bsdf type="roughplastic"/>
</bsdf>
```
The colour c at the surface's uv (the texture as it decodes it: an 8-bit image without `raw` is sRGB-decoded, as in
Mitsuba) gives the normal 2c - 1 relative to the shading frame, whose first axis follows dp/du; (0.5, 0.5, 1) leaves
the surface as it is. The frame, the side checks, the flip and the shadowing term are Mitsuba 3.9.1's
(kernels/bsdfs/perturb.h). Bsdf row (kernels/bsdfs/normalmap.h): p.normalmap = normalmap(_tex), child (row offset),
options.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from ..textures.texture import param
from .composite import Composite

FLIP, SHADOW = 1, 2     # kernels/bsdfs/perturb.h's PERTURB_FLIP, PERTURB_SHADOW


def perturb_options(props) -> int:
    return (FLIP if props.get_bool("flip_invalid_normals", True) else 0) | \
        (SHADOW if props.get_bool("use_shadowing_function", True) else 0)


@register("bsdf", "normalmap", fmt="mitsuba")
class NormalMap(Composite):
    kernel = "bsdfs/normalmap.h"
    METHODS = ("eval", "pdf", "sample", "albedo", "normal")
    PARAMS = [("normalmap", "texture"), ("child", "int"), ("options", "uint")]
    owner = '<bsdf type="normalmap">'

    def __init__(self, props, children, spec):
        self.read_children(spec, children, (1,), ("normalmap",))
        self.texture = self.textures.get("normalmap")
        if self.texture is not None and props.has("normalmap"):
            raise SceneError("normalmap given both as a colour and as a texture", props.location("normalmap"))
        if self.texture is None and not props.has("normalmap"):
            raise SceneError(f"{self.owner} needs a normal map: a nested <texture name=\"normalmap\"> (or an "
                             f"<rgb name=\"normalmap\">)", getattr(spec, "location", None))
        self.color = np.asarray(props.get_color("normalmap", np.array([0.5, 0.5, 1.0])), np.float64)
        if not np.all(np.isfinite(self.color)):
            raise SceneError(f"normalmap must be finite, got {self.color.tolist()}", props.location("normalmap"))
        self.options = perturb_options(props)

    def fill(self, p, row, textures):
        p["child"] = self.child_offsets[0]
        p["options"] = self.options
        param(p, "normalmap", self.color, self.texture, textures)
        return True    # the shading frame must follow dp/du (SHAPE_NEEDS_UV), as Mitsuba's does
