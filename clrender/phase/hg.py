"""Mitsuba 3's Henyey-Greenstein phase function.

```xml
<phase type="hg">
    <float name="g" value="0.8"/>            <!-- mean cosine of the scattering angle, in (-1, 1); default 0.8 as
                                                  Mitsuba's; > 0: forward, < 0: backward, 0: isotropic -->
</phase>
```
p(wo) = (1 - g²) / (4 pi (1 + g² + 2 g cos)^(3/2)), cos = dot(wo, wi) with wi pointing back along the path.
Kernel: kernels/phase/hg.h (sampled by inverting its CDF in the cosine: weight 1).
"""
from ..errors import SceneError
from ..scene.registry import register
from .phase import Phase


@register("phase", "hg", fmt="mitsuba")
class HenyeyGreenstein(Phase):
    kernel = "phase/hg.h"
    PARAMS = [("g", "float")]

    def __init__(self, props, children, spec):
        self.g = props.get_float("g", 0.8)
        if not -1 < self.g < 1:
            raise SceneError(f'<phase type="hg">: g must lie in (-1, 1) (exclusive), got {self.g}', props.location("g"))

    def fill(self, row) -> None:
        row["hg"]["g"] = self.g
