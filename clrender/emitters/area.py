"""Area light on a mesh or sphere (nested in its `<mesh>`): uniform radiance on the side its shading normal
faces (one-sided). Points are sampled by picking a triangle in proportion to its area, then a uniform point
on it; the area density is converted to solid angle with dist² / |cos at the light|.

```xml
<mesh type="obj">
    <string name="filename" value="light.obj"/>
    <emitter type="area">
        <color name="radiance" value="10, 10, 10"/>   <!-- required -->
    </emitter>
</mesh>
```
Emitter row (kernels/emitters/area.h): p.area.radiance.xyz = radiance, radiance_tex = NONE (or, for a textured
radiance, the texture's row: the shape then gets SHAPE_NEEDS_UV), shape = the emitting shape, which samples its
own surface (its area distribution is packed with it: clrender/shapes/shape.py).
"""
import numpy as np

from ..device import dispatch
from ..scene.registry import register
from ..textures.texture import param
from .emitter import Emitter, color_or_texture, luminance, nonnegative_color


@register("emitter", "area")
class AreaEmitter(Emitter):
    kernel = "emitters/area.h"
    PARAMS = [("radiance", "texture")]
    FLAGS = ("SURFACE",)
    texture = None   # a texture object for the radiance (Mitsuba files), else the constant `radiance`

    def __init__(self, props, children, spec):
        self.radiance = nonnegative_color(props, "radiance")

    def pack(self, ctx, shape_index, shape, shape_row):
        row = super().pack(ctx, shape_index, shape, shape_row)
        if self.texture is not None and shape_row is not None:   # hits and samples on the shape need its uv
            shape_row["flags"] |= dispatch.flag_defines()["SHAPE_NEEDS_UV"]
        return row

    def fill(self, p, row, ctx, shape):
        param(p, "radiance", self.radiance, self.texture, ctx.textures)

    def selection_power(self, radius, area):
        # one-sided Lambertian emitter; a texture counts with its largest value (an upper bound)
        scale = self.texture.max_value() if self.texture is not None else luminance(self.radiance)
        return np.pi * area * scale


@register("emitter", "area", fmt="mitsuba")
class MitsubaAreaEmitter(AreaEmitter):
    """Mitsuba 3's area light, nested in (or referenced by) a shape: one-sided, on the side its normals face. The
    radiance may be a texture over the shape's uv (sampling stays uniform by area).

    ```xml
    <shape type="obj">
        ...
        <emitter type="area">
            <rgb name="radiance" value="10, 10, 10"/>   <!-- default 1; rgb, spectrum (emitter convention) or float -->
            <!-- or <texture type="bitmap" name="radiance"> ... </texture> -->
        </emitter>
    </shape>
    ```
    """
    children = ("texture",)

    def __init__(self, props, children, spec):
        self.radiance, self.texture = color_or_texture(props, children, "radiance", '<emitter type="area">')
