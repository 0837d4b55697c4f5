"""Mitsuba 3's smooth plastic: a diffuse base under a smooth dielectric coating (a delta specular lobe and a
diffuse lobe scaled by the coating's transmittance, with internal scattering accounted for).

```xml
<bsdf type="plastic">
    <rgb name="diffuse_reflectance" value="0.5"/>    <!-- default 0.5; may be a <texture> -->
    <rgb name="specular_reflectance" value="1"/>     <!-- default 1; may be a <texture> -->
    <float name="int_ior" value="1.49"/>             <!-- or a name: default "polypropylene" (1.49) -->
    <float name="ext_ior" value="1.000277"/>         <!-- or a name: default "air" -->
    <boolean name="nonlinear" value="false"/>        <!-- internal scattering shifts colours; default false -->
</bsdf>
```
With eta = int_ior / ext_ior, F the dielectric Fresnel reflectance and Fdr(eta) the diffuse (hemispherically
averaged) Fresnel reflectance:
    specular (delta):  specular_reflectance * F(cos_i) towards the mirror direction
    diffuse:           f = d / (1 - Fdr_int) * (1 - F(cos_i)) (1 - F(cos_o)) / (pi eta^2),  Fdr_int = Fdr(1/eta)
                       (nonlinear: d / (1 - d Fdr_int))
Sampling picks the specular lobe with probability F s / (F s + (1 - F)(1 - s)), s = mean(specular) /
(mean(diffuse) + mean(specular)) (Mitsuba's rule; the means of textures are their averages over uv).
Bsdf row (kernels/bsdfs/plastic.h): p.plastic = diffuse(_tex), specular(_tex), eta, fdr_int, spec_weight,
nonlinear.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from ..textures.texture import param
from .bsdf import Bsdf
from .ior import read_mitsuba_iors


def fresnel_diffuse_reflectance(eta: float) -> float:
    """Fdr(eta): the Fresnel reflectance averaged over a cosine-weighted hemisphere of incident directions, by the
    published fits Mitsuba 3 uses (Egan & Hilgeman 1973 for eta < 1, d'Eon & Irving 2011 above)."""
    if eta < 1:
        return -1.4399 * eta * eta + 0.7099 * eta + 0.6681 + 0.0636 / eta
    x = 1.0 / eta
    return 0.919317 + x * (-3.4793 + x * (6.75335 + x * (-7.80989 + x * (4.98554 + x * -1.36881))))


def colour_texture_children(children, names, owner):
    """{name: nested texture} for the textures named in `names` (nested BSDFs are not textures)."""
    from .bsdf import Bsdf as _Bsdf
    from .mitsuba_params import named_textures

    return named_textures([c for c in children if not isinstance(c, _Bsdf)], names, owner)


def texture_mean(tex):
    """The average colour of a texture over the unit uv square (on a grid: textures are evaluated on the host)."""
    g = (np.arange(64) + 0.5) / 64
    uv = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    return np.asarray(tex.eval(uv), np.float64).reshape(-1, 3).mean(0)


class CoatedBase(Bsdf):
    """What plastic and roughplastic read alike."""
    children = ("texture",)
    owner = ""

    def read_common(self, props, children):
        tex = colour_texture_children(children, ("diffuse_reflectance", "specular_reflectance"), self.owner)
        self.diffuse, self.diffuse_tex, d_mean = self._colour(props, "diffuse_reflectance", 0.5, tex)
        self.specular, self.specular_tex, s_mean = self._colour(props, "specular_reflectance", 1.0, tex)
        self.int_ior, self.ext_ior = read_mitsuba_iors(props, "polypropylene", "air")
        if self.int_ior == self.ext_ior:
            raise SceneError(f"{self.owner}: int_ior and ext_ior must differ, both are {self.int_ior}",
                             props.location("int_ior") or getattr(props, "owner_location", None))
        self.eta = self.int_ior / self.ext_ior
        self.nonlinear = bool(props.get_bool("nonlinear", False))
        self.spec_weight = s_mean / (d_mean + s_mean) if d_mean + s_mean > 0 else 0.5

    def _colour(self, props, name, default, textures):
        tex = textures.get(name)
        if tex is not None and props.has(name):
            raise SceneError(f"{name} given both as a colour and as a texture", props.location(name))
        value = np.asarray(props.get_color(name, np.full(3, default)), np.float64)
        if np.any(value < 0) or not np.all(np.isfinite(value)):
            raise SceneError(f"{name} of {self.owner} must be non-negative, got {value.tolist()}",
                             props.location(name))
        mean = float(value.mean()) if tex is None else float(texture_mean(tex).mean())
        return value, tex, mean

    def fill_common(self, p, textures):
        uv = param(p, "diffuse", self.diffuse, self.diffuse_tex, textures)
        uv |= param(p, "specular", self.specular, self.specular_tex, textures)
        p["eta"], p["spec_weight"], p["nonlinear"] = self.eta, self.spec_weight, int(self.nonlinear)
        return uv


@register("bsdf", "plastic", fmt="mitsuba")
class Plastic(CoatedBase):
    kernel = "bsdfs/plastic.h"
    PARAMS = [("diffuse", "texture"), ("specular", "texture"), ("eta", "float"), ("fdr_int", "float"),
              ("spec_weight", "float"), ("nonlinear", "uint")]
    FLAGS = ("DELTA", "DIFFUSE")
    METHODS = ("eval", "pdf", "sample", "albedo")
    owner = '<bsdf type="plastic">'

    def __init__(self, props, children, spec):
        self.read_common(props, children)
        self.fdr_int = fresnel_diffuse_reflectance(1.0 / self.eta)

    def fill(self, p, row, textures):
        p["fdr_int"] = self.fdr_int
        return self.fill_common(p, textures)
