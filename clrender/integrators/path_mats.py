"""Path tracing by BSDF sampling alone: emission counts where a sampled ray reaches it.

```xml
<integrator type="path_mats">
    <integer name="maxDepth" value="-1"/>   <!-- path segments at most; -1 (default): no limit -->
</integrator>
```
Kernel: kernels/integrators/path_mats.h (the loop of path.h). Russian roulette as Nori (path.py).
"""
from ..scene.registry import register
from .path import PathIntegrator


@register("integrator", "path_mats")
class PathMats(PathIntegrator):
    kernel = "path_mats"
