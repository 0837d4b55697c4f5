"""Mitsuba 3's homogeneous medium: the same extinction and albedo everywhere.

```xml
<medium type="homogeneous" id="fog">
    <rgb name="sigma_t" value="1, 1, 1"/>    <!-- extinction per scene unit, float or colour; default 1 -->
    <rgb name="albedo" value="0.75"/>        <!-- single-scattering albedo sigma_s / sigma_t, float or colour;
                                                  default 0.75 -->
    <float name="scale" value="1"/>          <!-- multiplies sigma_t; default 1 -->
    <boolean name="sample_emitters" value="true"/>   <!-- scattering vertices sample lights; default true -->
    <boolean name="has_spectral_extinction" value="true"/>   <!-- accepted as Mitsuba's; default true -->
    <phase type="isotropic"/>                <!-- default isotropic; or hg -->
</medium>
<shape type="obj"> ... <ref id="fog" name="interior"/> </shape>   <!-- or a nested <medium name="interior"> -->
<sensor type="perspective"> ... <ref id="fog"/> </sensor>          <!-- the camera's medium -->
```
`sigma_t` and `albedo` are constants: a `<volume>` (grid or constant volume) belongs in a heterogeneous medium
(clrender/media/heterogeneous.py). `has_spectral_extinction` picks Mitsuba's estimator for colour extinction;
clrender samples free flights the same way either way (one-sample MIS over the three channels: kernels/integrators/media.h), which
converges to the same image. Kernel: kernels/media/homogeneous.h.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .medium import Medium


@register("medium", "homogeneous", fmt="mitsuba")
class Homogeneous(Medium):
    kernel = "media/homogeneous.h"
    PARAMS = [("sigma_t", "float4"), ("albedo", "float4")]
    FLAGS = ("HOMOGENEOUS",)
    METHODS = ("sigma_t", "albedo")   # free flights in closed form: no majorant, no clip

    def __init__(self, props, children, spec):
        self._read_phase(children, spec)
        scale = self._read_common(props)
        sigma_t = np.asarray(props.get_color("sigma_t", np.ones(3), unbounded=True), np.float64)
        self.albedo = np.asarray(props.get_color("albedo", np.full(3, 0.75)), np.float64)
        if np.any(sigma_t < 0) or not np.all(np.isfinite(sigma_t)):
            raise SceneError(f"sigma_t must be non-negative and finite, got {sigma_t.tolist()}",
                             props.location("sigma_t") if props.has("sigma_t") else spec.location)
        if np.any(self.albedo < 0) or np.any(self.albedo > 1):
            raise SceneError(f"albedo must lie in [0, 1], got {self.albedo.tolist()}", props.location("albedo"))
        self.sigma_t = sigma_t * scale
        if not np.all(np.isfinite(self.sigma_t)) or np.any(self.sigma_t > 3.4e38):
            raise SceneError(f"sigma_t * scale is beyond single precision: {self.sigma_t.tolist()}",
                             props.location("scale") if props.has("scale") else spec.location)

    def fill(self, row, ctx=None) -> None:
        row["homogeneous"]["sigma_t"][:3] = self.sigma_t
        row["homogeneous"]["albedo"][:3] = self.albedo
