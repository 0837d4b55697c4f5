"""Box filter.

```xml
<rfilter type="box">
    <float name="radius" value="0.5"/>   <!-- default 0.5 (one pixel) -->
</rfilter>
```
"""
import numpy as np

from ..scene.registry import register
from .filter import Filter
from .validate import positive_radius


@register("rfilter", "box")
class BoxFilter(Filter):
    kernel = "filters/box.h"

    def __init__(self, props, children, spec):
        self.radius = positive_radius(props, 0.5)

    def eval(self, x):
        return (np.abs(x) <= self.radius).astype(np.float64)


@register("rfilter", "box", fmt="mitsuba")
class MitsubaBoxFilter(BoxFilter):
    """Mitsuba 3's box filter: one pixel, no parameters.

    ```xml
    <rfilter type="box"/>
    ```
    """

    def __init__(self, props, children, spec):
        self.radius = 0.5
