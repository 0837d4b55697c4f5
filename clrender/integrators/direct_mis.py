"""One emitter sample and one BSDF sample per camera hit, combined by the balance heuristic.

```xml
<integrator type="direct_mis"/>
```
Kernel: kernels/integrators/direct_mis.h.
"""
from ..scene.registry import register
from .integrator import Integrator


@register("integrator", "direct_mis")
class DirectMis(Integrator):
    kernel = "direct_mis"
    needs_emitter = True  # sees nothing but emitted light

    def __init__(self, props, children, spec):
        pass
