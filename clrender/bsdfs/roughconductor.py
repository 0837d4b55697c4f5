"""Mitsuba 3's rough conductor: a Beckmann or GGX microfacet BRDF with the conductor Fresnel term of eta + i k.

```xml
<bsdf type="roughconductor">
    <string name="distribution" value="ggx"/>      <!-- beckmann (default) or ggx -->
    <float name="alpha" value="0.2"/>              <!-- roughness (float or texture), default 0.1 -->
    <!-- or anisotropic: <float name="alpha_u" value="0.05"/> <float name="alpha_v" value="0.3"/> -->
    <boolean name="sample_visible" value="true"/>  <!-- sample visible normals, default true -->
    <string name="material" value="Cu"/>           <!-- as conductor: a preset, or eta and k; default "none" -->
    <rgb name="specular_reflectance" value="1"/>    <!-- colour or texture, default 1 -->
</bsdf>
```
Bsdf row (kernels/bsdfs/roughconductor.h): p.roughconductor = eta, k, specular_reflectance (+ _tex), alpha_u,
alpha_v (+ _tex), distribution, sample_visible.
"""
from ..scene.registry import register
from .bsdf import Bsdf
from .conductor import read_eta_k
from .mitsuba_params import Distribution, color_or_texture, fill_color, named_textures


@register("bsdf", "roughconductor", fmt="mitsuba")
class RoughConductor(Bsdf):
    kernel = "bsdfs/roughconductor.h"
    PARAMS = [("eta", "float4"), ("k", "float4"), ("specular_reflectance", "texture"),
              ("alpha_u", "float_texture"), ("alpha_v", "float_texture"),
              ("distribution", "uint"), ("sample_visible", "uint")]
    FLAGS = ("GLOSSY",)
    children = ("texture",)

    def __init__(self, props, children, spec):
        tex = named_textures(children, ("specular_reflectance",) + Distribution.NAMES, '<bsdf type="roughconductor">')
        where = getattr(spec, "location", None)
        self.eta, self.k = read_eta_k(props, where)
        self.specular_reflectance = color_or_texture(props, tex, "specular_reflectance")
        self.distribution = Distribution(props, tex, where)

    def fill(self, p, row, textures):
        p["eta"][:3], p["k"][:3] = self.eta, self.k
        uses = fill_color(p, "specular_reflectance", self.specular_reflectance, textures)
        return self.distribution.fill(p, textures) | uses
