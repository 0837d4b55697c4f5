"""One emitter sample per camera hit (plus the emission the camera ray sees); delta BSDFs get none.

```xml
<integrator type="direct_ems"/>
```
Kernel: kernels/integrators/direct_ems.h.
"""
from ..scene.registry import register
from .integrator import Integrator


@register("integrator", "direct_ems")
class DirectEms(Integrator):
    kernel = "direct_ems"
    needs_emitter = True  # sees nothing but emitted light

    def __init__(self, props, children, spec):
        pass
