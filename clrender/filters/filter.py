"""What the reconstruction filters share: the 1-D table the kernel samples offsets from.

Filters are applied by filter importance sampling (see kernels/filter.h): the kernel draws a sample's
offset from the pixel centre from a piecewise-constant density proportional to |f| and weights the sample by
f/p, so every filter, negative lobes included, converges to the same image as Nori's splatting.
"""
from __future__ import annotations

import abc

import numpy as np

TABLE_BINS = 256


class Filter(abc.ABC):
    """A filter plugin declares its kernel half (`kernel`: <prefix>_eval(cam, x) in kernels/filters/<prefix>.h,
    reached through the generated filter_profile_eval) and the parameters it packs into the Camera row's union
    (`PARAMS`, written by `fill`)."""
    kernel = ""
    PARAMS: list = []
    radius = 0.5

    def pack(self, row, table) -> None:
        """Write the filter's fields of the Camera row (its sampling table has len(table) - 1 bins)."""
        from ..device import dispatch

        row["filter_type"] = dispatch.tag_of(type(self))
        row["filter_bins"] = len(table) - 1
        row["filter_radius"] = self.radius
        if self.PARAMS:
            self.fill(row[dispatch.member_of(type(self))])

    def fill(self, p) -> None:
        """Write the declared parameters into `p` (this filter's member of the Camera row's union)."""

    @abc.abstractmethod
    def eval(self, x: np.ndarray) -> np.ndarray:
        """The filter's 1-D profile f(x) (the kernel's filter_eval_1d computes the same)."""

    def sampling_table(self, bins: int = TABLE_BINS) -> np.ndarray:
        """CDF (bins+1 entries) of |f| integrated over each bin (by a fine midpoint rule)."""
        sub = 32
        x = -self.radius + (np.arange(bins * sub) + 0.5) * (2 * self.radius / (bins * sub))
        mass = np.abs(self.eval(x)).reshape(bins, sub).sum(axis=1)
        cdf = np.concatenate([[0.0], np.cumsum(mass)])
        cdf /= cdf[-1]
        cdf[-1] = 1.0
        return cdf.astype(np.float32)


def with_guide(cdf: np.ndarray) -> np.ndarray:
    """The sampling table as the render kernel reads it: the CDF (bins+1 entries) followed by a guide of
    ``bins`` entries, guide[k] = the last bin i < bins with cdf[i] <= k/bins (as a float; exact below 2**24).

    kernels/filter.h's filter_sample_guided starts at guide[floor(u*bins)] and steps to the bin that the
    bisection of filter_sample would find (the last i with cdf[i] <= u): on average one step, where the
    bisection took log2(bins) unpredictable branches (measured: 14 % of a Cornell box render)."""
    cdf = np.asarray(cdf, np.float32)
    bins = len(cdf) - 1
    u = (np.arange(bins, dtype=np.float64) / bins).astype(np.float32)
    guide = np.searchsorted(cdf[:bins], u, side="right") - 1
    guide = np.clip(guide, 0, bins - 1).astype(np.float32)
    return np.concatenate([cdf, guide]).astype(np.float32)
