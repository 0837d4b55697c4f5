"""Average visibility: one uniform hemisphere direction at the first hit; 1 if nothing is hit within
`length`, else 0. Escaping camera rays give 1.

```xml
<integrator type="av">
    <float name="length" value="1"/>   <!-- required: how far occluders count -->
</integrator>
```
"""
from ..errors import SceneError
from ..scene.registry import register
from .integrator import Integrator


@register("integrator", "av")
class AverageVisibility(Integrator):
    kernel = "av"
    PARAMS = [("length", "float")]

    def __init__(self, props, children, spec):
        self.length = props.get_float("length")
        if not self.length > 0:
            raise SceneError(f"length must be positive, got {self.length}", props.location("length"))

    def fill(self, p):
        p["length"] = self.length
