"""Path tracing with multiple importance sampling of emitter and BSDF samples (balance heuristic).

```xml
<integrator type="path_mis">
    <integer name="maxDepth" value="-1"/>   <!-- path segments at most; -1 (default): no limit -->
</integrator>
```
Kernel: kernels/integrators/path_mis.h (the loop of path.h). Russian roulette as Nori (path.py).
"""
from ..scene.registry import register
from .path import PathIntegrator


@register("integrator", "path_mis")
class PathMis(PathIntegrator):
    kernel = "path_mis"
