"""Ambient occlusion: one cosine-weighted direction at the first hit; 1 if it escapes the scene, else 0
(an estimate of the integral of V cos / pi). Escaping camera rays give 1.

```xml
<integrator type="ao"/>
```
"""
from ..scene.registry import register
from .integrator import Integrator


@register("integrator", "ao")
class AmbientOcclusion(Integrator):
    kernel = "ao"

    def __init__(self, props, children, spec):
        pass
