"""Mitsuba 3's thin dielectric: a thin sheet of glass (a window pane, a soap film) that reflects the sum of its
two interfaces' inter-reflections and lets the rest through undeviated. A delta BSDF.

```xml
<bsdf type="thindielectric">
    <string name="int_ior" value="bk7"/>            <!-- a number or a name (bsdfs/ior.py), default "bk7" -->
    <string name="ext_ior" value="air"/>            <!-- default "air" -->
    <rgb name="specular_reflectance" value="1"/>    <!-- colour or texture, default 1 -->
    <rgb name="specular_transmittance" value="1"/>  <!-- colour or texture, default 1 -->
</bsdf>
```
Bsdf row (kernels/bsdfs/thindielectric.h): p.thindielectric, the same fields as p.dielectric.
"""
from ..scene.registry import register
from .bsdf import Bsdf
from .dielectric import DIELECTRIC_PARAMS, MitsubaSmoothDielectric


@register("bsdf", "thindielectric", fmt="mitsuba")
class ThinDielectric(MitsubaSmoothDielectric, Bsdf):
    kernel = "bsdfs/thindielectric.h"
    PARAMS = DIELECTRIC_PARAMS
    FLAGS = ("DELTA", "TRANSMISSION")
    # null_transmission: the sheet's transmittance T, which volpath's shadow rays carry through it (as Mitsuba's)
    METHODS = ("sample", "null_transmission")
