"""Gaussian filter (Nori's default): f(x) = max(0, exp(-x²/2σ²) - exp(-r²/2σ²)), separable.

```xml
<rfilter type="gaussian">
    <float name="radius" value="2"/>     <!-- default 2 -->
    <float name="stddev" value="0.5"/>   <!-- default 0.5 -->
</rfilter>
```
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .filter import Filter
from .validate import positive_radius


@register("rfilter", "gaussian")
class GaussianFilter(Filter):
    kernel = "filters/gaussian.h"
    PARAMS = [("stddev", "float"), ("floor", "float")]

    def __init__(self, props=None, children=(), spec=None):
        if props is None:  # the camera's default filter
            self.radius, self.stddev = 2.0, 0.5
        else:
            self.radius = positive_radius(props, 2.0)
            self.stddev = float(props.get_float("stddev", 0.5))
            if not self.stddev > 0:
                raise SceneError(f"stddev must be positive, got {self.stddev}", props.location("stddev"))
        self.floor = float(np.exp(-self.radius ** 2 / (2 * self.stddev ** 2)))
        if props is not None and not 1.0 - self.floor >= 1e-6:
            # the kernel subtracts the floor in single precision: the weights would all be 0, the image black
            raise SceneError(f"gaussian filter of radius {self.radius:g} is too narrow for its stddev "
                             f"{self.stddev:g}: its weights vanish in single precision (the radius must be at least "
                             f"0.0015 stddev)", props.location("radius" if props.has("radius") else "stddev"))

    def eval(self, x):
        x = np.asarray(x, np.float64)
        v = np.maximum(0.0, np.exp(-x * x / (2 * self.stddev ** 2)) - self.floor)
        return np.where(np.abs(x) <= self.radius, v, 0.0)

    def fill(self, p):
        p["stddev"], p["floor"] = self.stddev, self.floor


@register("rfilter", "gaussian", fmt="mitsuba")
class MitsubaGaussianFilter(GaussianFilter):
    """Mitsuba 3's gaussian filter (its default): cut off at 4 standard deviations.

    ```xml
    <rfilter type="gaussian">
        <float name="stddev" value="0.5"/>   <!-- default 0.5; the radius is 4 stddev -->
    </rfilter>
    ```
    """

    def __init__(self, props=None, children=(), spec=None):
        self.stddev = 0.5 if props is None else float(props.get_float("stddev", 0.5))
        if not 0 < self.stddev < 250:
            raise SceneError(f"stddev must be positive (and below 250), got {self.stddev}", props.location("stddev"))
        self.radius = 4.0 * self.stddev
        self.floor = float(np.exp(-self.radius ** 2 / (2 * self.stddev ** 2)))

    @classmethod
    def default(cls):
        return cls()
