"""One BSDF sample per camera hit, counting the emission of what it reaches.

```xml
<integrator type="direct_mats"/>
```
Kernel: kernels/integrators/direct_mats.h.
"""
from ..scene.registry import register
from .integrator import Integrator


@register("integrator", "direct_mats")
class DirectMats(Integrator):
    kernel = "direct_mats"
    needs_emitter = True  # sees nothing but emitted light

    def __init__(self, props, children, spec):
        pass
