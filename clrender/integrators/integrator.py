"""What the integrator plugins share: the kernel they select and the parameters they pack.

`kernel` names kernels/integrators/<kernel>.h (the program is built with -DINTEGRATOR=<kernel>); `PARAMS` declares
the integrator's parameter struct, a member of SceneInfo's union `p` (sd->info->p.<kernel>), generated like a
BSDF's (clrender/device/dispatch.py); `fill(p)` writes it.
"""
from __future__ import annotations

NO_LIMIT = 0xFFFFFFFF


class Integrator:
    #: name of kernels/integrators/<kernel>.h
    kernel = ""
    PARAMS: list = []
    #: path segments at most (path integrators' maxDepth); NO_LIMIT = none
    max_depth = NO_LIMIT
    rr_depth = 3

    def pack(self, info) -> None:
        """Write the integrator's fields of the SceneInfo row `info`."""
        from ..device import dispatch

        info["max_depth"] = self.max_depth
        info["rr_depth"] = self.rr_depth
        if self.PARAMS:
            self.fill(info[dispatch.member_of(type(self))])

    def fill(self, p) -> None:
        """Write the declared parameters into `p` (this integrator's member of SceneInfo's union)."""
