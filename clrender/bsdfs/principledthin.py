"""Mitsuba 3's thin principled BSDF (principledthin): Burley's thin-surface model as Mitsuba 3.9 evaluates it, a
two-sided sheet with a GGX specular reflection, a GGX "transmission" that reflects about the microfacet and continues
on the other side (no bending; roughness scaled by 0.65 eta - 0.35), a diffuse lobe with retro-reflection, flatness
and sheen, and a Lambertian transmission.

```xml
<bsdf type="principledthin">
    <rgb name="base_color" value="0.7, 0.1, 0.1"/>  <!-- default 0.5; may be a <texture> -->
    <float name="roughness" value="0.15"/>          <!-- default 0.5 -->
    <float name="anisotropic" value="0"/>           <!-- default 0 -->
    <float name="spec_trans" value="0.8"/>          <!-- default 0 (the specular lobes' weight) -->
    <float name="diff_trans" value="0.3"/>          <!-- default 0, in [0, 2] (2: only diffuse transmission) -->
    <float name="eta" value="1.33"/>                <!-- default 1.5 -->
    <float name="spec_tint" value="0"/>             <!-- default 0 -->
    <float name="sheen" value="0"/>                 <!-- default 0 -->
    <float name="sheen_tint" value="0"/>            <!-- default 0 -->
    <float name="flatness" value="0"/>              <!-- default 0 -->
    <float name="specular_reflectance_sampling_rate" value="1"/>    <!-- default 1 -->
    <float name="specular_transmittance_sampling_rate" value="1"/>  <!-- default 1 -->
    <float name="diffuse_reflectance_sampling_rate" value="1"/>     <!-- default 1 -->
    <float name="diffuse_transmittance_sampling_rate" value="1"/>   <!-- default 1 -->
</bsdf>
```
Every parameter but the sampling rates may be a nested `<texture name="...">` (eta too, as in Mitsuba). Values are
taken as given (Mitsuba does not clamp them). The formulas are in kernels/bsdfs/principledthin.h. Bsdf row:
p.principledthin = base_color(_tex), each of FLOAT_PARAMS as a float_texture (roughness(_tex), ...), the four
sampling rates.
"""
from ..scene.registry import register
from .bsdf import Bsdf
from .principled import fill_parameters, read_parameters, read_rates
from ..errors import SceneError

#: (name, Mitsuba's default): float_texture parameters of the row (b->p.principledthin.<name>)
FLOAT_PARAMS = (("roughness", 0.5), ("anisotropic", 0.0), ("spec_trans", 0.0), ("spec_tint", 0.0), ("sheen", 0.0),
                ("sheen_tint", 0.0), ("flatness", 0.0), ("diff_trans", 0.0), ("eta", 1.5))
RATES = (("specular_reflectance_sampling_rate", "spec_refl_srate"),
         ("specular_transmittance_sampling_rate", "spec_trans_srate"),
         ("diffuse_reflectance_sampling_rate", "diff_refl_srate"),
         ("diffuse_transmittance_sampling_rate", "diff_trans_srate"))
OWNER = '<bsdf type="principledthin">'


@register("bsdf", "principledthin", fmt="mitsuba")
class PrincipledThin(Bsdf):
    kernel = "bsdfs/principledthin.h"
    PARAMS = [("base_color", "texture")] + [(name, "float_texture") for name, _ in FLOAT_PARAMS] + \
        [(field, "float") for _, field in RATES]
    FLAGS = ("GLOSSY", "DIFFUSE", "TRANSMISSION")   # always, as in Mitsuba (whatever spec_trans and diff_trans)
    METHODS = ("eval", "pdf", "sample", "albedo")
    children = ("texture",)

    def __init__(self, props, children, spec):
        self.base_color, self.floats, given = read_parameters(props, children, FLOAT_PARAMS, OWNER)
        eta, tex = self.floats["eta"]
        if tex is None and not eta > 0:
            raise SceneError(f"eta must be positive, got {eta}", props.location("eta"))
        self.has_anisotropic = given("anisotropic")
        self.rates = read_rates(props, RATES)

    def fill(self, p, row, textures):
        uses = fill_parameters(p, self, FLOAT_PARAMS, textures)
        for field, v in self.rates.items():
            p[field] = v
        # anisotropic roughness runs along dp/du (the shading frame follows the parametrisation then)
        return uses | self.has_anisotropic
