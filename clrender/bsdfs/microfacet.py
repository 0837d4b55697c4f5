"""Nori's microfacet model: a diffuse base plus a Beckmann specular lobe with dielectric Fresnel.

f = kd/pi + ks D(h) F(h.wi) G1(wi,h) G1(wo,h) / (4 cos(theta_i) cos(theta_o)),  ks = 1 - max(kd),
with D the Beckmann distribution, F the dielectric Fresnel for extIOR -> intIOR and G1 the Smith-Beckmann
rational fit. Sampling picks the specular lobe with probability ks; the pdf is the mixture of both.

```xml
<bsdf type="microfacet">
    <float name="alpha" value="0.1"/>         <!-- Beckmann roughness, default 0.1 -->
    <float name="intIOR" value="1.5046"/>     <!-- default 1.5046 -->
    <float name="extIOR" value="1.000277"/>   <!-- default 1.000277 -->
    <color name="kd" value="0.5, 0.5, 0.5"/>  <!-- diffuse albedo, default 0.5 -->
</bsdf>
```
A nested `<texture type="checkerboard_color" name="kd">` may replace kd (then ks = 1 - the largest
component of either texture colour).
Bsdf row (kernels/bsdfs/microfacet.h): p.microfacet = kd, kd_tex (NONE, or the texture's row in the textures
table), alpha, int_ior, ext_ior, ks.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .bsdf import Bsdf
from ..textures.texture import param, texture_child
from .ior import read_iors


@register("bsdf", "microfacet")
class Microfacet(Bsdf):
    kernel = "bsdfs/microfacet.h"
    PARAMS = [("kd", "texture"), ("alpha", "float"), ("int_ior", "float"), ("ext_ior", "float"), ("ks", "float")]
    FLAGS = ("DIFFUSE", "GLOSSY")
    METHODS = ("eval", "pdf", "sample", "albedo")
    children = ("texture",)

    def __init__(self, props, children, spec):
        self.texture = texture_child(children, "kd", '<bsdf type="microfacet">')
        if self.texture is not None and props.has("kd"):
            raise SceneError("kd given both as a color and as a texture", props.location("kd"))
        self.alpha = float(props.get_float("alpha", 0.1))
        if not 0 < self.alpha <= 10:
            raise SceneError(f"alpha must be in (0, 10], got {self.alpha}", props.location("alpha"))
        self.int_ior, self.ext_ior = read_iors(props)
        self.kd = np.asarray(props.get_color("kd", np.full(3, 0.5)), np.float64)
        if np.any(self.kd < 0) or np.any(self.kd > 1):
            raise SceneError(f"kd must be within [0, 1], got {self.kd.tolist()}", props.location("kd"))
        self.ks = 1.0 - float(self.kd.max())
        if self.texture is not None:
            if self.texture.max_value() > 1:
                raise SceneError("a kd texture must stay within [0, 1]", getattr(self.texture.spec, "location", None))
            self.ks = 1.0 - self.texture.max_value()

    def fill(self, p, row, textures):
        p["alpha"], p["int_ior"], p["ext_ior"], p["ks"] = self.alpha, self.int_ior, self.ext_ior, self.ks
        return param(p, "kd", self.kd, self.texture, textures)
