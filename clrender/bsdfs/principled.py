"""Mitsuba 3's principled BSDF (Burley's "Disney" model as Mitsuba 3.9 evaluates it): a diffuse lobe with
retro-reflection (and Hanrahan-Krueger flattening), sheen, a GGX main specular lobe (anisotropic, with the principled
Fresnel blend of dielectric, tinted and metallic Schlick terms), a GTR1 clearcoat and rough transmission.

```xml
<bsdf type="principled">
    <rgb name="base_color" value="0.8, 0.2, 0.1"/>   <!-- default 0.5; may be a <texture> -->
    <float name="roughness" value="0.3"/>           <!-- default 0.5 -->
    <float name="anisotropic" value="0"/>           <!-- default 0 (0: isotropic) -->
    <float name="metallic" value="0"/>              <!-- default 0 -->
    <float name="spec_trans" value="0"/>            <!-- default 0 (1: only the transmitting lobe) -->
    <float name="specular" value="0.5"/>            <!-- default 0.5, gives eta; or <float name="eta" .../> -->
    <float name="spec_tint" value="0"/>             <!-- default 0 -->
    <float name="sheen" value="0"/>                 <!-- default 0 -->
    <float name="sheen_tint" value="0"/>            <!-- default 0 -->
    <float name="flatness" value="0"/>              <!-- default 0 -->
    <float name="clearcoat" value="0"/>             <!-- default 0 -->
    <float name="clearcoat_gloss" value="0"/>       <!-- default 0 -->
    <float name="main_specular_sampling_rate" value="1"/>        <!-- default 1 -->
    <float name="clearcoat_sampling_rate" value="1"/>            <!-- default 1 (Mitsuba's code; its docs say 0) -->
    <float name="diffuse_reflectance_sampling_rate" value="1"/>  <!-- default 1 -->
</bsdf>
```
Every parameter but eta, specular and the sampling rates may be a nested `<texture name="...">` (floats read the
texture's float view, Mitsuba's eval_1). As in Mitsuba: eta and specular exclude each other, eta = 2 / (1 -
sqrt(0.08 specular)) - 1; with a transmitting lobe (spec_trans given, not the float 0) eta = 1 becomes 1.001 and
specular = 0 becomes 1e-3. Values outside [0, 1] are taken as given (Mitsuba does not clamp them).
The formulas are in kernels/bsdfs/principled.h. Bsdf row: p.principled = base_color(_tex), each of FLOAT_PARAMS as
a float_texture (roughness(_tex), ...), eta, the three sampling rates, has_spec_trans.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .bsdf import Bsdf
from .mitsuba_params import color_or_texture, fill_color, float_or_texture, named_textures

#: (name, Mitsuba's default): float_texture parameters of the row (b->p.principled.<name>)
FLOAT_PARAMS = (("roughness", 0.5), ("anisotropic", 0.0), ("metallic", 0.0), ("spec_trans", 0.0),
                ("spec_tint", 0.0), ("sheen", 0.0), ("sheen_tint", 0.0), ("flatness", 0.0), ("clearcoat", 0.0),
                ("clearcoat_gloss", 0.0))
RATES = (("main_specular_sampling_rate", "spec_srate"), ("clearcoat_sampling_rate", "clearcoat_srate"),
         ("diffuse_reflectance_sampling_rate", "diffuse_srate"))
OWNER = '<bsdf type="principled">'


def specular_to_eta(specular: float) -> float:
    return 2.0 / (1.0 - np.sqrt(0.08 * specular)) - 1.0


def read_parameters(props, children, float_params, owner):
    """(base_color, {name: (value, texture or None)}, given(name)) of the principled BSDFs: base_color a colour or
    a texture, the others floats or textures (a texture's float view, Mitsuba's eval_1); given(name) is Mitsuba's
    get_flag: the parameter is given, and not as the float 0."""
    names = ("base_color",) + tuple(n for n, _ in float_params)
    tex = named_textures(children, names, owner)
    base_color = color_or_texture(props, tex, "base_color", 0.5)
    floats = {name: float_or_texture(props, tex, name, default, positive=False) for name, default in float_params}

    def given(n):
        return n in tex or (props.has(n) and not (props.tag(n) == "float" and floats[n][0] == 0))

    return base_color, floats, given


def read_rates(props, rates):
    out = {}
    for name, field in rates:
        v = float(props.get_float(name, 1.0))
        if not (v >= 0 and np.isfinite(v)):
            raise SceneError(f"{name} must be non-negative, got {v}", props.location(name))
        out[field] = v
    return out


def fill_parameters(p, bsdf, float_params, textures) -> bool:
    """Write base_color and the float parameters (each a constant or a texture); whether a texture is read."""
    uses = fill_color(p, "base_color", bsdf.base_color, textures)
    for name, _ in float_params:
        uses |= fill_color(p, name, bsdf.floats[name], textures)
    return uses


@register("bsdf", "principled", fmt="mitsuba")
class Principled(Bsdf):
    kernel = "bsdfs/principled.h"
    PARAMS = [("base_color", "texture")] + [(name, "float_texture") for name, _ in FLOAT_PARAMS] + [
              ("eta", "float"), ("spec_srate", "float"), ("clearcoat_srate", "float"), ("diffuse_srate", "float"),
              ("has_spec_trans", "uint")]
    FLAGS = ("GLOSSY", "DIFFUSE")
    METHODS = ("eval", "pdf", "sample", "albedo")
    children = ("texture",)

    def __init__(self, props, children, spec):
        self.base_color, self.floats, given = read_parameters(props, children, FLOAT_PARAMS, OWNER)
        self.has_spec_trans = given("spec_trans")
        self.has_anisotropic = given("anisotropic")
        if props.has("eta") and props.has("specular"):
            raise SceneError(f"{OWNER} takes either eta or specular (they set the same index of refraction), not "
                             "both", props.location("specular"))
        if props.has("eta"):
            self.eta = float(props.get_float("eta"))
            if not (self.eta > 0 and np.isfinite(self.eta)):
                raise SceneError(f"eta must be positive, got {self.eta}", props.location("eta"))
            if self.has_spec_trans and self.eta == 1.0:
                self.eta = 1.001
        else:
            s = float(props.get_float("specular", 0.5))
            if not 0 <= s < 12.5:
                raise SceneError(f"specular must be in [0, 12.5) (it sets eta = 2 / (1 - sqrt(0.08 specular)) - 1), "
                                 f"got {s}", props.location("specular"))
            if self.has_spec_trans and s == 0.0:
                s = 1e-3
            self.eta = float(specular_to_eta(np.float32(s)))
        self.rates = read_rates(props, RATES)

    def own_capabilities(self):
        # the transmitting lobe exists when spec_trans is given (not as the float 0), as in Mitsuba
        return super().own_capabilities() | ({"TRANSMISSION"} if self.has_spec_trans else set())

    def fill(self, p, row, textures):
        uses = fill_parameters(p, self, FLOAT_PARAMS, textures)
        p["eta"] = self.eta
        for field, v in self.rates.items():
            p[field] = v
        p["has_spec_trans"] = int(self.has_spec_trans)
        # anisotropic roughness runs along dp/du (the shading frame follows the parametrisation then)
        return uses | self.has_anisotropic
