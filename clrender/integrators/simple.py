"""Nori's first integrator: one isotropic point light given inline, seen by a white diffuse world.
L = energy / (4 pi²) · max(0, cos θ) / d² · V.

```xml
<integrator type="simple">
    <point name="position" value="0, 5, 0"/>   <!-- required -->
    <color name="energy" value="100, 100, 100"/>  <!-- required: the light's power -->
</integrator>
```
"""
import numpy as np

from ..scene.registry import register
from .integrator import Integrator


@register("integrator", "simple")
class SimpleIntegrator(Integrator):
    kernel = "simple"
    PARAMS = [("position", "float4"), ("energy", "float4")]

    def __init__(self, props, children, spec):
        self.position = np.asarray(props.get_point("position"), np.float64)
        self.energy = np.asarray(props.get_color("energy"), np.float64)

    def fill(self, p):
        p["position"][:3] = self.position
        p["energy"][:3] = self.energy
