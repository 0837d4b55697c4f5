"""Mitsuba 3's smooth conductor: a mirror reflecting the conductor Fresnel term of the complex index eta + i k.

```xml
<bsdf type="conductor">
    <string name="material" value="Au"/>           <!-- a preset (MATERIALS), default "none": a 100% mirror -->
    <!-- or: <rgb name="eta" value="0.2, 0.9, 1.1"/> <rgb name="k" value="3.9, 2.4, 2.1"/>  (default 0 and 1) -->
    <rgb name="specular_reflectance" value="1"/>    <!-- colour or texture, default 1 -->
</bsdf>
```
Bsdf row (kernels/bsdfs/conductor.h): p.conductor = eta, k, specular_reflectance (+ _tex).
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .bsdf import Bsdf
from .mitsuba_params import color_or_texture, fill_color, named_textures

#: Mitsuba 3's conductor presets as its RGB variants see them: (eta, k) in linear sRGB, read from Mitsuba 3.9.1
#: itself (scalar_rgb: mi.traverse of a conductor with each material, which converts the measured spectra to RGB;
#: tests/mitsuba/make_bsdf_values.py --presets prints them again).
MATERIALS = {
    "a-C": ((2.94405, 2.22714, 1.96816), (0.887465, 0.799299, 0.81529)),
    "Ag": ((0.155276, 0.116728, 0.138388), (4.82835, 3.12222, 2.1469)),
    "Al": ((1.6575, 0.880405, 0.521244), (9.22381, 6.2695, 4.837)),
    "AlAs": ((3.6053, 3.23294, 2.21632), (0.000679437, 0, 0.00751271)),
    "AlAs_palik": ((3.6053, 3.23294, 2.21632), (0.000679437, 0, 0.00751271)),
    "AlSb": ((0, 4.13937, 4.66925), (0, 0.0940091, 1.30057)),
    "AlSb_palik": ((0, 4.13937, 4.66925), (0, 0.0940091, 1.30057)),
    "Au": ((0.143036, 0.375307, 1.44205), (3.983, 2.38556, 1.60336)),
    "Be": ((4.18501, 3.18503, 2.78406), (3.83547, 3.01012, 2.86899)),
    "Be_palik": ((4.18501, 3.18503, 2.78406), (3.83547, 3.01012, 2.86899)),
    "Cr": ((4.36967, 2.91651, 1.6549), (5.20655, 4.23131, 3.7547)),
    "CsI": ((2.1449, 1.70232, 1.66243), (0, 0, 0)),
    "CsI_palik": ((2.1449, 1.70232, 1.66243), (0, 0, 0)),
    "Cu": ((0.201005, 0.92375, 1.10222), (3.91326, 2.45305, 2.14209)),
    "Cu_palik": ((0.213229, 0.919715, 1.10241), (3.92187, 2.45733, 2.13658)),
    "Cu2O": ((3.55177, 2.94987, 2.75188), (0.114207, 0.193897, 0.606134)),
    "Cu2O_palik": ((3.55177, 2.94987, 2.75188), (0.114207, 0.193897, 0.606134)),
    "CuO": ((3.24754, 2.44781, 2.21022), (0.52109, 0.570031, 0.722179)),
    "CuO_palik": ((3.24754, 2.44781, 2.21022), (0.52109, 0.570031, 0.722179)),
    "d-C": ((2.70872, 2.31883, 2.2289), (0, 0, 0)),
    "d-C_palik": ((2.70872, 2.31883, 2.2289), (0, 0, 0)),
    "Hg": ((2.39894, 1.44003, 0.90957), (6.32759, 4.37192, 3.42176)),
    "Hg_palik": ((2.39894, 1.44003, 0.90957), (6.32759, 4.37192, 3.42176)),
    "HgTe": ((4.77904, 3.2312, 2.6599), (1.63161, 1.58081, 1.72929)),
    "HgTe_palik": ((4.77904, 3.2312, 2.6599), (1.63161, 1.58081, 1.72929)),
    "Ir": ((3.0863, 2.08219, 1.61791), (5.59215, 4.06709, 3.26731)),
    "Ir_palik": ((3.0863, 2.08219, 1.61791), (5.59215, 4.06709, 3.26731)),
    "K": ((0.0640432, 0.0464098, 0.0381849), (2.1042, 1.34894, 0.913126)),
    "K_palik": ((0.0640432, 0.0464098, 0.0381849), (2.1042, 1.34894, 0.913126)),
    "Li": ((0.265791, 0.195618, 0.220949), (3.54015, 2.31112, 1.66861)),
    "Li_palik": ((0.265791, 0.195618, 0.220949), (3.54015, 2.31112, 1.66861)),
    "MgO": ((2.08958, 1.65072, 1.59488), (4.3327e-12, 0, 2.49865e-11)),
    "MgO_palik": ((2.08958, 1.65072, 1.59488), (4.3327e-12, 0, 2.49865e-11)),
    "Mo": ((4.48397, 3.52513, 2.77631), (4.11144, 3.42083, 3.15061)),
    "Mo_palik": ((4.48397, 3.52513, 2.77631), (4.11144, 3.42083, 3.15061)),
    "Na_palik": ((0.0602694, 0.0561409, 0.0619884), (3.17927, 2.11249, 1.57904)),
    "Nb": ((3.42007, 2.79009, 2.39563), (3.44139, 2.73767, 2.57975)),
    "Nb_palik": ((3.42007, 2.79009, 2.39563), (3.44139, 2.73767, 2.57975)),
    "Ni_palik": ((2.3673, 1.66337, 1.46708), (4.49881, 3.05015, 2.34544)),
    "Rh": ((2.58579, 1.86022, 1.55426), (6.78226, 4.70299, 3.97607)),
    "Rh_palik": ((2.58579, 1.86022, 1.55426), (6.78226, 4.70299, 3.97607)),
    "Se": ((4.05831, 2.84294, 2.82085), (0.75405, 0.638444, 0.521808)),
    "Se_palik": ((4.05831, 2.84294, 2.82085), (0.75405, 0.638444, 0.521808)),
    "SiC": ((3.17234, 2.52597, 2.47937), (7.53766e-07, 0, 1.01925e-05)),
    "SiC_palik": ((3.17234, 2.52597, 2.47937), (7.53766e-07, 0, 1.01925e-05)),
    "SnTe": ((4.52425, 1.98164, 1.28159), (0, 0, 0)),
    "SnTe_palik": ((4.52425, 1.98164, 1.28159), (0, 0, 0)),
    "Ta": ((2.06272, 2.39294, 2.62793), (2.40836, 1.74149, 1.94703)),
    "Ta_palik": ((2.06272, 2.39294, 2.62793), (2.40836, 1.74149, 1.94703)),
    "Te": ((7.39023, 4.4821, 2.63711), (3.25602, 3.52706, 3.29205)),
    "Te_palik": ((7.39023, 4.4821, 2.63711), (3.25602, 3.52706, 3.29205)),
    "ThF4": ((1.83071, 1.44223, 1.38765), (0, 0, 0)),
    "ThF4_palik": ((1.83071, 1.44223, 1.38765), (0, 0, 0)),
    "TiC": ((3.70053, 2.83742, 2.58229), (3.26564, 2.35159, 2.17279)),
    "TiC_palik": ((3.70053, 2.83742, 2.58229), (3.26564, 2.35159, 2.17279)),
    "TiN": ((1.64845, 1.15052, 1.37982), (3.36833, 1.9435, 1.10207)),
    "TiN_palik": ((1.64845, 1.15052, 1.37982), (3.36833, 1.9435, 1.10207)),
    "TiO2": ((3.45661, 2.80174, 2.90517), (0.000105265, 0, 0.000652887)),
    "TiO2_palik": ((3.45661, 2.80174, 2.90517), (0.000105265, 0, 0.000652887)),
    "VC": ((3.65757, 2.75274, 2.53267), (3.0683, 2.19869, 1.96319)),
    "VC_palik": ((3.65757, 2.75274, 2.53267), (3.0683, 2.19869, 1.96319)),
    "V_palik": ((4.27758, 3.51295, 2.76107), (3.4913, 2.88945, 3.11152)),
    "VN": ((2.8656, 2.11919, 1.94009), (3.03224, 2.05612, 1.61631)),
    "VN_palik": ((2.8656, 2.11919, 1.94009), (3.03224, 2.05612, 1.61631)),
    "W": ((4.37082, 3.30025, 2.99841), (3.50064, 2.60487, 2.27323)),
}


def read_eta_k(props, owner_location=None):
    """Mitsuba's rule: material "none" (the default) or eta/k given; a preset with eta/k is an error."""
    material = props.get_string("material", "none")
    if props.has("eta") or props.has("k") or material == "none":
        if material != "none":
            raise SceneError("give either material or eta and k, not both", props.location("material"))
        eta = np.asarray(props.get_color("eta", np.zeros(3), unbounded=True), np.float64)
        k = np.asarray(props.get_color("k", np.ones(3), unbounded=True), np.float64)
        for name, v in (("eta", eta), ("k", k)):
            if np.any(v < 0) or not np.all(np.isfinite(v)):
                raise SceneError(f"{name} must be non-negative and finite, got {v.tolist()}", props.location(name))
        return eta, k
    if material not in MATERIALS:
        raise SceneError(f"unknown conductor material {material!r}; known: none, {', '.join(MATERIALS)}",
                         props.location("material"))
    eta, k = MATERIALS[material]
    return np.array(eta, np.float64), np.array(k, np.float64)


@register("bsdf", "conductor", fmt="mitsuba")
class Conductor(Bsdf):
    kernel = "bsdfs/conductor.h"
    PARAMS = [("eta", "float4"), ("k", "float4"), ("specular_reflectance", "texture")]
    FLAGS = ("DELTA",)
    METHODS = ("sample",)
    children = ("texture",)

    def __init__(self, props, children, spec):
        tex = named_textures(children, ("specular_reflectance",), '<bsdf type="conductor">')
        self.eta, self.k = read_eta_k(props, getattr(spec, "location", None))
        self.specular_reflectance = color_or_texture(props, tex, "specular_reflectance")

    def fill(self, p, row, textures):
        p["eta"][:3], p["k"][:3] = self.eta, self.k
        return fill_color(p, "specular_reflectance", self.specular_reflectance, textures)
