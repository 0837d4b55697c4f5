"""Mitsuba 3's heterogeneous medium: extinction and albedo read from volumes (clrender/volumes/).

```xml
<medium type="heterogeneous" id="smoke">
    <volume type="gridvolume" name="sigma_t">           <!-- extinction per scene unit (times scale): a <volume>,
        <string name="filename" value="smoke.vol"/>          or a <float> / <rgb> (a constvolume); default 1 -->
        <transform name="to_world"> ... </transform>
    </volume>
    <float name="albedo" value="0.9"/>                  <!-- single-scattering albedo: a <volume>, <float> or <rgb>;
                                                             default 0.75 -->
    <float name="scale" value="200"/>                   <!-- multiplies sigma_t; default 1 -->
    <boolean name="sample_emitters" value="true"/>      <!-- scattering vertices sample lights; default true -->
    <boolean name="has_spectral_extinction" value="true"/>  <!-- accepted as Mitsuba's; default true -->
    <phase type="isotropic"/>                           <!-- default isotropic; or hg -->
</medium>
<shape type="cube"> ... <ref id="smoke" name="interior"/> </shape>
```
As Mitsuba 3.9.1's (src/media/heterogeneous.cpp): the majorant is scale times the sigma_t volume's largest value
over every channel (a volume's max_value), and the medium has extinction only inside the sigma_t volume's
world-space bounding box (to_world's image of the unit cube, or of the file's box with use_grid_bbox): so a
<float> sigma_t, a constvolume with the identity to_world, fills only the cube [0, 1]^3, as there. Free flights are
sampled by delta tracking against the majorant and shadow rays' transmittance estimated by ratio tracking
(kernels/integrators/media.h), with the homogeneous medium's spectral MIS over the channels; the estimator does not
depend on has_spectral_extinction, which converges to the same image. sigma_t must be non-negative and the albedo
within [0, 1] (checked over every voxel; a grid's values up to 1 % of its range outside it are clamped with a
warning). Kernel: kernels/media/heterogeneous.h.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from ..volumes.constvolume import ConstVolume
from .medium import Medium


@register("medium", "heterogeneous", fmt="mitsuba")
class Heterogeneous(Medium):
    kernel = "media/heterogeneous.h"
    PARAMS = [("sigma_t", "uint"), ("albedo", "uint"), ("scale", "float"), ("majorant", "float")]
    FLAGS = ()
    children = ("phase", "volume")

    def __init__(self, props, children, spec):
        self._read_phase(children, spec)
        volumes = self._volume_children(props, children, spec, ("sigma_t", "albedo"))
        self.sigma_t = volumes.get("sigma_t") or self._constant(props, "sigma_t", 1.0)
        self.albedo = volumes.get("albedo") or self._constant(props, "albedo", 0.75)
        self.scale = self._read_common(props)
        where = {n: (volumes[n].spec.location if n in volumes else
                     props.location(n) if props.has(n) else spec.location) for n in ("sigma_t", "albedo")}
        self._clamp_ringing("sigma_t", self.sigma_t, None, where["sigma_t"])
        self._clamp_ringing("albedo", self.albedo, 1.0, where["albedo"])
        if self.sigma_t.min_value() < 0:
            raise SceneError(f"sigma_t must be non-negative; its volume's smallest value is "
                             f"{self.sigma_t.min_value()}", where["sigma_t"])
        if self.albedo.min_value() < 0 or self.albedo.max_value() > 1:
            raise SceneError(f"albedo must lie in [0, 1]; its volume's values span [{self.albedo.min_value()}, "
                             f"{self.albedo.max_value()}]", where["albedo"])
        self.majorant = self.scale * self.sigma_t.max_value()
        if not np.isfinite(self.majorant) or self.majorant > 3.4e38:
            raise SceneError(f"sigma_t * scale is beyond single precision: majorant {self.majorant}",
                             props.location("scale") if props.has("scale") else spec.location)

    @staticmethod
    def _constant(props, name, default) -> ConstVolume:
        if not props.has(name):
            return ConstVolume.of(default, 1)
        value = props.get_color(name, unbounded=True)
        return ConstVolume.of(value, 1 if props.tag(name) == "float" else 3)

    def fill(self, row, ctx=None) -> None:
        p = row["heterogeneous"]
        p["sigma_t"] = self.sigma_t.pack(ctx)
        p["albedo"] = self.albedo.pack(ctx)
        p["scale"] = self.scale
        p["majorant"] = self.majorant
