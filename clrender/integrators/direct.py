"""Nori's `direct`: every point light exactly, each with a shadow ray.

```xml
<integrator type="direct"/>
```
Kernel: kernels/integrators/direct.h.
"""
from ..scene.registry import register
from .integrator import Integrator


@register("integrator", "direct")
class Direct(Integrator):
    kernel = "direct"
    needs_emitter = True  # sees nothing but emitted light

    def __init__(self, props, children, spec):
        pass
