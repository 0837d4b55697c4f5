"""Smooth dielectric interface (glass): reflects with probability F (unpolarised Fresnel), refracts
otherwise; refracted radiance is scaled by (eta_from / eta_to)². A delta BSDF.

```xml
<bsdf type="dielectric">
    <float name="intIOR" value="1.5046"/>     <!-- inside, default 1.5046 (BK7) -->
    <float name="extIOR" value="1.000277"/>   <!-- outside, default 1.000277 (air) -->
</bsdf>
```
Bsdf row (kernels/bsdfs/dielectric.h): p.dielectric = (int_ior, ext_ior).
"""
from ..scene.registry import register
from .bsdf import Bsdf
from .ior import read_iors


@register("bsdf", "dielectric")
class Dielectric(Bsdf):
    kernel = "bsdfs/dielectric.h"
    PARAMS = [("int_ior", "float"), ("ext_ior", "float")]
    FLAGS = ("DELTA",)
    METHODS = ("sample",)

    def __init__(self, props, children, spec):
        self.int_ior, self.ext_ior = read_iors(props)

    def fill(self, p, row, textures):
        p["int_ior"], p["ext_ior"] = self.int_ior, self.ext_ior
