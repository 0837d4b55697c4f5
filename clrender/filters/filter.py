"""What the reconstruction filters share: the 1-D table the kernel samples offsets from.

Filters are applied by filter importance sampling (see kernels/filter.h): the kernel draws a sample's
offset from the pixel centre from a piecewise-constant density proportional to |f| and weights the sample by
f/p, so every filter, negative lobes included, converges to the same image as Nori's splatting.
"""
from __future__ import annotations

import numpy as np

TABLE_BINS = 256


class Filter:
    filter_type = 0
    radius = 0.5
    p0 = p1 = p2 = 0.0

    def eval(self, x: np.ndarray) -> np.ndarray:  # pragma: no cover - every filter overrides it
        raise NotImplementedError

    def sampling_table(self, bins: int = TABLE_BINS) -> np.ndarray:
        """CDF (bins+1 entries) of |f| integrated over each bin (by a fine midpoint rule)."""
        sub = 32
        x = -self.radius + (np.arange(bins * sub) + 0.5) * (2 * self.radius / (bins * sub))
        mass = np.abs(self.eval(x)).reshape(bins, sub).sum(axis=1)
        cdf = np.concatenate([[0.0], np.cumsum(mass)])
        cdf /= cdf[-1]
        cdf[-1] = 1.0
        return cdf.astype(np.float32)
