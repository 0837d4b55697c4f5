"""Tent (triangle) filter: f(x) = max(0, 1 - |x|/r).

```xml
<rfilter type="tent">
    <float name="radius" value="1"/>   <!-- default 1 -->
</rfilter>
```
"""
import numpy as np

from ..scene.registry import register
from .filter import Filter
from .validate import positive_radius


@register("rfilter", "tent")
class TentFilter(Filter):
    kernel = "filters/tent.h"

    def __init__(self, props, children, spec):
        self.radius = positive_radius(props, 1.0)

    def eval(self, x):
        return np.maximum(0.0, 1.0 - np.abs(x) / self.radius)


@register("rfilter", "tent", fmt="mitsuba")
class MitsubaTentFilter(TentFilter):
    """Mitsuba 3's tent filter (the same parameter and default as ours).

    ```xml
    <rfilter type="tent">
        <float name="radius" value="1"/>   <!-- default 1 -->
    </rfilter>
    ```
    """
