"""Mitsuba 3's bump map adapter: the nested BSDF in the shading frame of a surface displaced by a height texture.

```xml
<bsdf type="bumpmap">
    <texture type="bitmap" name="height">                 <!-- one nested texture, any name: a bitmap -->
        <string name="filename" value="height.exr"/>
        <boolean name="raw" value="true"/>
    </texture>
    <float name="scale" value="1"/>                        <!-- default 1: multiplies the height's slope -->
    <boolean name="flip_invalid_normals" value="true"/>    <!-- default true -->
    <boolean name="use_shadowing_function" value="true"/>  <!-- default true -->
    <bsdf type="diffuse"/>
</bsdf>
```
The height is the texture as Mitsuba's float lookup reads it (a colour image's luminance); its uv gradient is the
slope of the bitmap's bilinear interpolation (Mitsuba's eval_1_grad, `nearest` has none; textures without a gradient
(checkerboard, ...) are an error, as they are for Mitsuba). With (gu, gv) = scale * that gradient, the surface's
dp/du and dp/dv get gu and gv as their components along the shading normal and the new normal is their cross
product, turned to the geometric normal's side; a constant height changes nothing. dp/du and dp/dv are Mitsuba's:
from the mesh's uvs, or where it has none its triangle's edges p1 - p0 and p2 - p0 (uv then being the barycentrics);
on a sphere 2 pi r along phi and pi r along theta. The rest (flip, side checks, shadowing) is kernels/bsdfs/perturb.h.
Bsdf row (kernels/bsdfs/bumpmap.h): p.bumpmap = tex (the height's row in the textures table), scale, child (row
offset), options.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from ..textures.bitmap import Bitmap
from .bsdf import Bsdf
from .composite import Composite, composite_depth
from .normalmap import perturb_options
from ..device import dispatch


@register("bsdf", "bumpmap", fmt="mitsuba")
class BumpMap(Composite):
    kernel = "bsdfs/bumpmap.h"
    METHODS = ("eval", "pdf", "sample", "albedo", "normal")
    PARAMS = [("tex", "uint"), ("scale", "float"), ("child", "int"), ("options", "uint")]
    owner = '<bsdf type="bumpmap">'

    def __init__(self, props, children, spec):
        where = getattr(spec, "location", None)
        self.bsdfs = [c for c in children if isinstance(c, Bsdf)]
        textures = [c for c in children if not isinstance(c, Bsdf)]
        if len(self.bsdfs) != 1:
            raise SceneError(f"{self.owner} needs exactly one nested <bsdf>, got {len(self.bsdfs)}", where)
        if len(textures) != 1:
            raise SceneError(f"{self.owner} needs exactly one nested <texture> (the height), got {len(textures)}",
                             getattr(getattr(textures[1], "spec", None), "location", where) if textures else where)
        tex = textures[0]
        if not isinstance(tex, Bitmap):
            tspec = getattr(tex, "spec", None)
            raise SceneError(f"{self.owner}: the height must be a <texture type=\"bitmap\">; Mitsuba 3.9 gives "
                             f"<texture type=\"{getattr(tspec, 'type', '?')}\"> no uv gradient (eval_1_grad) either",
                             getattr(tspec, "location", where))
        self.texture = tex.float_view()
        self.scale = props.get_float("scale", 1.0)
        if not np.isfinite(self.scale):
            raise SceneError(f"scale must be finite, got {self.scale}", props.location("scale"))
        self.options = perturb_options(props)
        depth, levels = composite_depth(self), dispatch.BSDF.composite_levels
        if depth > levels:
            raise SceneError(f"composite BSDFs (twosided, blendbsdf, mask, normalmap, bumpmap) nested {depth} deep; "
                             f"at most {levels} levels are supported", where)

    def fill(self, p, row, textures):
        p["tex"] = textures.add(self.texture)
        p["scale"] = self.scale
        p["child"] = self.child_offsets[0]
        p["options"] = self.options
        return True    # reads uv and dp/du, dp/dv
