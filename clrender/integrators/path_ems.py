"""Path tracing with emitter sampling at every non-delta vertex (emission reached by BSDF samples counts
only after delta bounces and for the camera ray).

```xml
<integrator type="path_ems">
    <integer name="maxDepth" value="-1"/>   <!-- path segments at most; -1 (default): no limit -->
</integrator>
```
Kernel: kernels/integrators/path_ems.h (the loop of path.h). Russian roulette as Nori (path.py).
"""
from ..scene.registry import register
from .path import PathIntegrator


@register("integrator", "path_ems")
class PathEms(PathIntegrator):
    kernel = "path_ems"
