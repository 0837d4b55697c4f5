"""Mitchell-Netravali filter (negative lobes; handled by signed sample weights).

```xml
<rfilter type="mitchell">
    <float name="radius" value="2"/>   <!-- default 2 -->
    <float name="B" value="0.3333"/>   <!-- default 1/3 -->
    <float name="C" value="0.3333"/>   <!-- default 1/3 -->
</rfilter>
```
"""
import numpy as np

from ..scene.registry import register
from .filter import Filter
from .validate import positive_radius


@register("rfilter", "mitchell")
class MitchellFilter(Filter):
    kernel = "filters/mitchell.h"
    PARAMS = [("B", "float"), ("C", "float")]

    def __init__(self, props, children, spec):
        self.radius = positive_radius(props, 2.0)
        self.B = float(props.get_float("B", 1.0 / 3.0))
        self.C = float(props.get_float("C", 1.0 / 3.0))

    def eval(self, x):
        B, C = self.B, self.C
        t = 2.0 * np.abs(np.asarray(x, np.float64)) / self.radius
        near = ((12 - 9 * B - 6 * C) * t ** 3 + (-18 + 12 * B + 6 * C) * t ** 2 + (6 - 2 * B)) / 6
        far = ((-B - 6 * C) * t ** 3 + (6 * B + 30 * C) * t ** 2 + (-12 * B - 48 * C) * t + (8 * B + 24 * C)) / 6
        return np.where(t < 1, near, np.where(t < 2, far, 0.0))

    def fill(self, p):
        p["B"], p["C"] = self.B, self.C


@register("rfilter", "mitchell", fmt="mitsuba")
class MitsubaMitchellFilter(MitchellFilter):
    """Mitsuba 3's Mitchell-Netravali filter (radius 2).

    ```xml
    <rfilter type="mitchell">
        <float name="B" value="0.3333"/>   <!-- default 1/3 -->
        <float name="C" value="0.3333"/>   <!-- default 1/3 -->
    </rfilter>
    ```
    """

    def __init__(self, props, children, spec):
        self.radius = 2.0
        self.B = float(props.get_float("B", 1.0 / 3.0))
        self.C = float(props.get_float("C", 1.0 / 3.0))


@register("rfilter", "catmullrom", fmt="mitsuba")
class MitsubaCatmullRomFilter(MitchellFilter):
    """Mitsuba 3's Catmull-Rom filter: the Mitchell-Netravali filter with B = 0, C = 0.5 (radius 2).

    ```xml
    <rfilter type="catmullrom"/>
    ```
    """

    def __init__(self, props, children, spec):
        self.radius, self.B, self.C = 2.0, 0.0, 0.5
