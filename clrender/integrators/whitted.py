"""Nori's Whitted-style integrator: emission plus one area-light sample at diffuse/microfacet hits; mirror and
dielectric hits continue along the sampled direction with probability 0.95 (divided by 0.95).

```xml
<integrator type="whitted"/>
```
Kernel: kernels/integrators/whitted.h.
"""
from ..scene.registry import register
from .integrator import Integrator


@register("integrator", "whitted")
class Whitted(Integrator):
    kernel = "whitted"
    needs_emitter = True  # sees nothing but emitted light

    def __init__(self, props, children, spec):
        pass
