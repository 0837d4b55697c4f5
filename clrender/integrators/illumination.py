"""The direct-illumination and path-tracing integrators (Nori's names; kernels/integrators/<name>.h).

```xml
<integrator type="direct_ems"/>    <!-- one emitter sample per camera hit -->
<integrator type="direct_mats"/>   <!-- one BSDF sample per camera hit -->
<integrator type="direct_mis"/>    <!-- both, balance heuristic -->
<integrator type="direct"/>        <!-- every point/distant light exactly (Nori's 'direct') -->
<integrator type="whitted"/>       <!-- direct at diffuse hits, specular chains continued with p = 0.95 -->
<integrator type="path_mats"/>     <!-- path tracing by BSDF sampling -->
<integrator type="path_ems"/>      <!-- path tracing with emitter sampling -->
<integrator type="path_mis">       <!-- path tracing with MIS of emitter and BSDF samples -->
    <integer name="maxDepth" value="-1"/>   <!-- path integrators: path segments at most; -1 (default) none -->
</integrator>
```
Russian roulette (path integrators) as Nori: from depth 3, continue with probability
min(max(throughput) eta², 0.99).
"""
from ..errors import SceneError
from ..scene.registry import register
from .integrator import NO_LIMIT, Integrator


class _Illumination(Integrator):
    takes_max_depth = False
    needs_emitter = True  # they see nothing but emitted light

    def __init__(self, props, children, spec):
        if self.takes_max_depth:
            depth = props.get_int("maxDepth", -1)
            if depth == 0 or depth < -1:
                raise SceneError(f"maxDepth must be -1 (no limit) or at least 1, got {depth}",
                                 props.location("maxDepth"))
            self.max_depth = NO_LIMIT if depth == -1 else depth


def _define(name, paths=False):
    cls = type(name, (_Illumination,), {"kernel": name, "takes_max_depth": paths, "__doc__": __doc__})
    return register("integrator", name)(cls)


for _name in ("direct_ems", "direct_mats", "direct_mis", "direct", "whitted"):
    _define(_name)
for _name in ("path_mats", "path_ems", "path_mis"):
    _define(_name, paths=True)
