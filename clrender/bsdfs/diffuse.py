"""Lambertian reflection: f = albedo / pi above the surface; cosine-weighted sampling.

```xml
<bsdf type="diffuse">
    <color name="albedo" value="0.5, 0.5, 0.5"/>   <!-- default 0.5 -->
</bsdf>
```
ETH variant: a nested `<texture type="checkerboard_color" name="albedo">` replaces the albedo colour
(see clrender/textures/). Bsdf row (kernels/bsdfs/diffuse.h): p.diffuse.albedo, albedo_tex (NONE, or the texture's
row in the textures table).
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .bsdf import Bsdf
from ..textures.texture import param, texture_child


@register("bsdf", "diffuse")
class Diffuse(Bsdf):
    kernel = "bsdfs/diffuse.h"
    PARAMS = [("albedo", "texture")]
    FLAGS = ("DIFFUSE",)
    METHODS = ("eval", "pdf", "sample", "albedo")
    children = ("texture",)

    def __init__(self, props, children, spec):
        self.texture = texture_child(children, "albedo", '<bsdf type="diffuse">')
        if self.texture is not None and props.has("albedo"):
            raise SceneError("albedo given both as a color and as a texture", props.location("albedo"))
        self.albedo = np.asarray(props.get_color("albedo", np.full(3, 0.5)), np.float64)
        if np.any(self.albedo < 0) or not np.all(np.isfinite(self.albedo)):
            raise SceneError(f"albedo must be non-negative, got {self.albedo.tolist()}", props.location("albedo"))

    @classmethod
    def default(cls, albedo: float = 0.5):
        """The BSDF of a shape that names none."""
        obj = cls.__new__(cls)
        obj.albedo = np.full(3, float(albedo))
        obj.texture = None
        obj.spec = None
        return obj

    def fill(self, p, row, textures):
        return param(p, "albedo", self.albedo, self.texture, textures)


@register("bsdf", "diffuse", fmt="mitsuba")
class MitsubaDiffuse(Diffuse):
    """Mitsuba 3's smooth diffuse BSDF (one-sided, as ours).

    ```xml
    <bsdf type="diffuse">
        <rgb name="reflectance" value="0.5"/>   <!-- rgb, spectrum or float; default 0.5 -->
        <!-- or a texture: <texture type="..." name="reflectance"> ... </texture>, or <ref name="reflectance" id="..."/> -->
    </bsdf>
    ```
    """

    def __init__(self, props, children, spec):
        self.texture = texture_child(children, "reflectance", '<bsdf type="diffuse">')
        if self.texture is not None and props.has("reflectance"):
            raise SceneError("reflectance given both as a colour and as a texture", props.location("reflectance"))
        self.albedo = np.asarray(props.get_color("reflectance", np.full(3, 0.5)), np.float64)
        if np.any(self.albedo < 0) or not np.all(np.isfinite(self.albedo)):
            raise SceneError(f"reflectance must be non-negative, got {self.albedo.tolist()}",
                             props.location("reflectance"))
