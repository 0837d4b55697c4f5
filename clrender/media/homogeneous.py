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
`sigma_t` is one value everywhere: a `<volume>` of it belongs in a heterogeneous medium
(clrender/media/heterogeneous.py); `albedo` may be a nested `<volume name="albedo">` (a `gridvolume` or
`constvolume`, looked up at each scattering point, as Mitsuba 3.9.1 allows). `has_spectral_extinction` picks Mitsuba's estimator for colour extinction;
clrender samples free flights the same way either way (one-sample MIS over the three channels: kernels/integrators/media.h), which
converges to the same image. Kernel: kernels/media/homogeneous.h.
"""
import numpy as np

from ..device import layout
from ..errors import SceneError
from ..scene.registry import register
from .medium import Medium


@register("medium", "homogeneous", fmt="mitsuba")
class Homogeneous(Medium):
    kernel = "media/homogeneous.h"
    PARAMS = [("sigma_t", "float4"), ("albedo", "float4"), ("albedo_volume", "uint")]
    FLAGS = ("HOMOGENEOUS",)
    METHODS = ("sigma_t", "albedo")   # free flights in closed form: no majorant, no clip
    children = ("phase", "volume")

    def __init__(self, props, children, spec):
        self._read_phase(children, spec)
        scale = self._read_common(props)
        sigma_t = np.asarray(props.get_color("sigma_t", np.ones(3), unbounded=True), np.float64)
        volumes = self._volume_children(props, children, spec, ("sigma_t", "albedo"))
        if "sigma_t" in volumes:
            raise SceneError("a homogeneous medium's sigma_t is one value everywhere; a <volume> of it belongs in a "
                             '<medium type="heterogeneous">', volumes["sigma_t"].spec.location)
        #: Mitsuba's homogeneous albedo may vary in space (a volume: its docs' textured subsurface scene)
        self.albedo_volume = volumes.get("albedo")
        if self.albedo_volume is not None:
            where = self.albedo_volume.spec.location
            self._clamp_ringing("albedo", self.albedo_volume, 1.0, where)
            lo, hi = self.albedo_volume.min_value(), self.albedo_volume.max_value()
            if lo < 0 or hi > 1:
                raise SceneError(f"albedo must lie in [0, 1]; its volume's values span [{lo}, {hi}]", where)
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
        row["homogeneous"]["albedo_volume"] = layout.NONE if self.albedo_volume is None else \
            self.albedo_volume.pack(ctx)
