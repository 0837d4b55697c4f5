"""Mitsuba 3's rough dielectric: a Beckmann or GGX microfacet interface that reflects and refracts (Walter et al.
2007), e.g. frosted glass.

```xml
<bsdf type="roughdielectric">
    <string name="distribution" value="ggx"/>       <!-- beckmann (default) or ggx -->
    <float name="alpha" value="0.2"/>               <!-- roughness (float or texture), default 0.1 -->
    <!-- or anisotropic: <float name="alpha_u" value="0.05"/> <float name="alpha_v" value="0.3"/> -->
    <boolean name="sample_visible" value="true"/>   <!-- sample visible normals, default true -->
    <string name="int_ior" value="bk7"/>            <!-- a number or a name (bsdfs/ior.py), default "bk7" -->
    <string name="ext_ior" value="air"/>            <!-- default "air" -->
    <rgb name="specular_reflectance" value="1"/>    <!-- colour or texture, default 1 -->
    <rgb name="specular_transmittance" value="1"/>  <!-- colour or texture, default 1 -->
</bsdf>
```
Bsdf row (kernels/bsdfs/roughdielectric.h): p.roughdielectric = specular_reflectance, specular_transmittance
(+ _tex), int_ior, ext_ior, alpha_u, alpha_v (+ _tex), distribution, sample_visible.
"""
from ..scene.registry import register
from .bsdf import Bsdf
from .ior import read_mitsuba_iors
from .mitsuba_params import Distribution, color_or_texture, fill_color, named_textures


@register("bsdf", "roughdielectric", fmt="mitsuba")
class RoughDielectric(Bsdf):
    kernel = "bsdfs/roughdielectric.h"
    # in this order to fit 80 bytes: scalars fill the gap between a texture's index and the next float4
    PARAMS = [("specular_reflectance", "texture"), ("int_ior", "float"), ("ext_ior", "float"),
              ("alpha_u", "float_texture"), ("specular_transmittance", "texture"), ("alpha_v", "float_texture"),
              ("distribution", "uint"), ("sample_visible", "uint")]
    FLAGS = ("GLOSSY", "TRANSMISSION")
    children = ("texture",)

    def __init__(self, props, children, spec):
        names = ("specular_reflectance", "specular_transmittance") + Distribution.NAMES
        tex = named_textures(children, names, '<bsdf type="roughdielectric">')
        self.int_ior, self.ext_ior = read_mitsuba_iors(props)
        self.specular_reflectance = color_or_texture(props, tex, "specular_reflectance")
        self.specular_transmittance = color_or_texture(props, tex, "specular_transmittance")
        self.distribution = Distribution(props, tex, getattr(spec, "location", None))

    def fill(self, p, row, textures):
        p["int_ior"], p["ext_ior"] = self.int_ior, self.ext_ior
        uses = fill_color(p, "specular_reflectance", self.specular_reflectance, textures)
        uses |= fill_color(p, "specular_transmittance", self.specular_transmittance, textures)
        return self.distribution.fill(p, textures) | uses
