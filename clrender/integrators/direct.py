"""Nori's `direct`: every point light exactly, each with a shadow ray.

```xml
<integrator type="direct"/>
```
Kernel: kernels/integrators/direct.h. Mitsuba 3's `direct` (emitter and BSDF samples with MIS) is MitsubaDirect
below, with its own XML form and kernel.
"""
from ..errors import SceneError
from ..scene.registry import register
from .integrator import Integrator


@register("integrator", "direct")
class Direct(Integrator):
    kernel = "direct"
    needs_emitter = True  # sees nothing but emitted light

    def __init__(self, props, children, spec):
        pass


@register("integrator", "direct", fmt="mitsuba")
class MitsubaDirect(Integrator):
    """Mitsuba 3's `direct`: direct illumination at the camera ray's first hit, by emitter and BSDF samples.

    ```xml
    <integrator type="direct">
        <integer name="shading_samples" value="1"/>   <!-- sets both counts below (default 1) -->
        <integer name="emitter_samples" value="1"/>   <!-- emitter samples per hit (default: shading_samples) -->
        <integer name="bsdf_samples" value="1"/>      <!-- BSDF samples per hit (default: shading_samples) -->
        <boolean name="hide_emitters" value="false"/> <!-- camera rays see through emitters, not the environment -->
    </integrator>
    ```
    The two techniques are combined by the power heuristic on their pdfs times their shares of the samples, each
    sample weighted 1/count (Mitsuba's src/integrators/direct.cpp). One difference from the textbook estimator is
    kept because Mitsuba 3.9 renders it: an emitter sample of a delta light (point, spot, directional) is not
    divided by emitter_samples, so such lights come out emitter_samples times brighter. hide_emitters as for `path`
    (path.py). Kernel: kernels/integrators/direct_mitsuba.h.
    """
    kernel = "direct_mitsuba"
    PARAMS = [("emitter_samples", "uint"), ("bsdf_samples", "uint"), ("hide_emitters", "uint")]
    needs_emitter = True  # sees nothing but emitted light

    def __init__(self, props, children, spec):
        where = '<integrator type="direct">'
        if props.has("shading_samples") and (props.has("emitter_samples") or props.has("bsdf_samples")):
            raise SceneError(f"{where}: give either shading_samples or emitter_samples/bsdf_samples, not both",
                             props.location("shading_samples"))
        shading = self._count(props, "shading_samples", 1)
        self.emitter_samples = self._count(props, "emitter_samples", shading)
        self.bsdf_samples = self._count(props, "bsdf_samples", shading)
        if self.emitter_samples + self.bsdf_samples == 0:
            given = [n for n in ("emitter_samples", "bsdf_samples", "shading_samples") if props.has(n)]
            raise SceneError(f"{where}: needs at least one emitter or BSDF sample (both counts are 0)",
                             props.location(given[0]) if given else spec.location)
        self.hide_emitters = props.get_bool("hide_emitters", False)

    @staticmethod
    def _count(props, name, default):
        n = props.get_int(name, default)
        if not 0 <= n <= 1024:
            raise SceneError(f'<integrator type="direct">: {name} must be between 0 and 1024, got {n}',
                             props.location(name))
        return n

    def fill(self, p):
        p["emitter_samples"] = self.emitter_samples
        p["bsdf_samples"] = self.bsdf_samples
        p["hide_emitters"] = int(self.hide_emitters)
