"""Lanczos windowed sinc filter (Mitsuba 3's ``lanczos``): f(x) = sinc(x) sinc(x / lobes) for |x| < lobes, with
sinc(x) = sin(pi x) / (pi x); negative lobes are handled by signed sample weights (clrender/filters/filter.py).

```xml
<rfilter type="lanczos">
    <integer name="lobes" value="3"/>   <!-- default 3; the radius is the number of lobes -->
</rfilter>
```
Camera row (kernels/filters/lanczos.h): p.lanczos.lobes.
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .filter import Filter


@register("rfilter", "lanczos", fmt="mitsuba")
class LanczosFilter(Filter):
    kernel = "filters/lanczos.h"
    PARAMS = [("lobes", "float")]

    def __init__(self, props, children, spec):
        self.lobes = props.get_float("lobes", 3.0)
        if not 0 < self.lobes <= 100:
            raise SceneError(f"lobes must be positive (at most 100), got {self.lobes:g}", props.location("lobes"))
        self.radius = float(self.lobes)

    def eval(self, x):
        x = np.abs(np.asarray(x, np.float64))
        return np.where(x < self.lobes, np.sinc(x) * np.sinc(x / self.lobes), 0.0)

    def fill(self, p):
        p["lobes"] = self.lobes
