"""What the path-tracing integrators share (path_mats.py, path_ems.py, path_mis.py): Nori's optional maxDepth, and
Russian roulette as Nori's (from depth 3, continue with probability min(max(throughput) eta², 0.99)).
The kernel is kernels/integrators/path.h, selected by <name>.h.
"""
from ..errors import SceneError
from .integrator import NO_LIMIT, Integrator


class PathIntegrator(Integrator):
    needs_emitter = True  # sees nothing but emitted light

    def __init__(self, props, children, spec):
        depth = props.get_int("maxDepth", -1)
        if depth == 0 or depth < -1:
            raise SceneError(f"maxDepth must be -1 (no limit) or at least 1, got {depth}", props.location("maxDepth"))
        self.max_depth = NO_LIMIT if depth == -1 else depth
