"""Mitsuba 3's `rawconstant` texture: one value everywhere, with no colour conversion and no range check.

```xml
<texture type="rawconstant" name="normalmap">
    <vector name="value" value="0.5, 0.5, 1.0"/>   <!-- required: a <vector> (3 values) or a <float> (all three) -->
</texture>
```
As Mitsuba 3.9.1's (src/spectra/rawconstant.cpp): a `<float>` is broadcast to the three channels and is also what
a float parameter (a roughness, a blend weight) reads; a `<vector>` read as a float is an error there, and here.
Mitsuba's own test scenes use it for a flat `normalmap` (0.5, 0.5, 1).

Texture row (kernels/textures/rawconstant.h): p.rawconstant.value = (value, 0).
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .texture import Texture


@register("texture", "rawconstant", fmt="mitsuba")
class RawConstant(Texture):
    kernel = "textures/rawconstant.h"
    PARAMS = [("value", "float4")]

    def __init__(self, props, children, spec):
        if not props.has("value"):
            raise SceneError('<texture type="rawconstant"> needs a "value": a <float> or a 3-D <vector>',
                             spec.location)
        tag = props.tag("value")
        if tag == "float":
            self.value = np.full(3, props.get_float("value"))
        elif tag in ("vector", "point"):
            self.value = np.asarray(props.get_vector("value") if tag == "vector" else props.get_point("value"),
                                    np.float64)
        else:
            raise SceneError(f'<texture type="rawconstant">: "value" is a <{tag}>; expected a <float> or a 3-D '
                             f'<vector> (as in Mitsuba)', props.location("value"))
        self.channels = 1 if tag == "float" else 3
        self.location = spec.location

    def max_value(self) -> float:
        return float(self.value.max())

    def make_float_view(self) -> "RawConstant":
        if self.channels == 3:
            raise SceneError('<texture type="rawconstant"> with a 3-D value cannot fill a float parameter (Mitsuba '
                             '3.9.1: "eval_1() is not defined for 3D-valued textures"); give it a <float>',
                             self.location)
        return self

    def eval(self, uv) -> np.ndarray:
        uv = np.asarray(uv, np.float64)
        return np.broadcast_to(self.value, uv.shape[:-1] + (3,)).copy()

    def fill(self, p) -> None:
        p["value"] = (*self.value, 0.0)
