"""Smooth dielectric interface (glass): reflects with probability F (unpolarised Fresnel), refracts
otherwise; refracted radiance is scaled by (eta_from / eta_to)². A delta BSDF.

```xml
<bsdf type="dielectric">
    <float name="intIOR" value="1.5046"/>     <!-- inside, default 1.5046 (BK7) -->
    <float name="extIOR" value="1.000277"/>   <!-- outside, default 1.000277 (air) -->
</bsdf>
```
Mitsuba 3's form (scene files read as Mitsuba):
```xml
<bsdf type="dielectric">
    <string name="int_ior" value="water"/>          <!-- a number or a name (bsdfs/ior.py), default "bk7" -->
    <float name="ext_ior" value="1.000277"/>        <!-- a number or a name, default "air" -->
    <rgb name="specular_reflectance" value="1"/>    <!-- factor on reflection (colour or texture), default 1 -->
    <rgb name="specular_transmittance" value="1"/>  <!-- factor on refraction (colour or texture), default 1 -->
</bsdf>
```
Bsdf row (kernels/bsdfs/dielectric.h): p.dielectric = specular_reflectance, specular_transmittance (+ _tex),
int_ior, ext_ior.
"""
from ..device import layout
from ..scene.registry import register
from .bsdf import Bsdf
from .ior import read_iors, read_mitsuba_iors
from .mitsuba_params import color_or_texture, fill_color, named_textures

#: the parameters of Mitsuba's smooth dielectrics (dielectric, thindielectric): one row layout for both
DIELECTRIC_PARAMS = [("specular_reflectance", "texture"), ("specular_transmittance", "texture"),
                     ("int_ior", "float"), ("ext_ior", "float")]


@register("bsdf", "dielectric")
class Dielectric(Bsdf):
    kernel = "bsdfs/dielectric.h"
    PARAMS = DIELECTRIC_PARAMS
    FLAGS = ("DELTA", "TRANSMISSION")
    METHODS = ("sample",)

    def __init__(self, props, children, spec):
        self.int_ior, self.ext_ior = read_iors(props)

    def fill(self, p, row, textures):
        p["int_ior"], p["ext_ior"] = self.int_ior, self.ext_ior
        for name in ("specular_reflectance", "specular_transmittance"):
            p[name][:3] = 1.0
            p[name + "_tex"] = layout.NONE
        return False


class MitsubaSmoothDielectric:
    """Mitsuba's int_ior/ext_ior and the two specular factors (dielectric, thindielectric)."""
    children = ("texture",)

    def __init__(self, props, children, spec):
        tex = named_textures(children, ("specular_reflectance", "specular_transmittance"),
                             f'<bsdf type="{getattr(spec, "type", "dielectric")}">')
        self.int_ior, self.ext_ior = read_mitsuba_iors(props)
        self.specular_reflectance = color_or_texture(props, tex, "specular_reflectance")
        self.specular_transmittance = color_or_texture(props, tex, "specular_transmittance")

    def fill(self, p, row, textures):
        p["int_ior"], p["ext_ior"] = self.int_ior, self.ext_ior
        uses = fill_color(p, "specular_reflectance", self.specular_reflectance, textures)
        return fill_color(p, "specular_transmittance", self.specular_transmittance, textures) | uses


@register("bsdf", "dielectric", fmt="mitsuba")
class MitsubaDielectric(MitsubaSmoothDielectric, Dielectric):
    pass
