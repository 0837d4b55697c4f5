"""What the integrator plugins share: the kernel they select and the parameters they pack."""
from __future__ import annotations

import numpy as np

NO_LIMIT = 0xFFFFFFFF


class Integrator:
    #: name of kernels/integrators/<kernel>.h
    kernel = ""
    #: path segments at most (path integrators' maxDepth); NO_LIMIT = none
    max_depth = NO_LIMIT
    rr_depth = 3

    def iparams(self) -> np.ndarray:
        """Two float4 of integrator parameters (SceneInfo.iparams)."""
        return np.zeros((2, 4), np.float32)
