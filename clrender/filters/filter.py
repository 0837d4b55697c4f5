"""What the reconstruction filters share: the profile both films evaluate, and the 1-D table the kernel samples
offsets from.

A splatting film (kernels/splat.cl, the default) weights each sample, placed uniformly in its pixel, into every
pixel within the radius by f(dx) f(dy), as Nori and Mitsuba do; a filter-sampling film (kernels/filter.h: adaptive
renders, the wavefront driver, box filters) draws a sample's offset from the pixel centre from a piecewise-constant
density proportional to |f| and weights the sample by f/p. Both converge to the same image, negative lobes included.
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

    def splat_pool_factor(self, n: int = 64) -> float:
        """How much a splatting film (kernels/splat.cl) understates the variance of a sum of many pixels when each
        pixel's variance is taken as independent: E[S1^2] / E[S2], S1 and S2 the sums of a sample's weights and
        squared weights over the pixels it reaches, over sample positions uniform in the pixel (about 3 for
        Mitsuba's Gaussian; 1 for a box)."""
        w = self._splat_weights(n)
        s1 = w.sum(axis=1)
        s2 = (w * w).sum(axis=1)
        # 2-D weights are products: S1 = s1x s1y, S2 = s2x s2y over independent x and y
        return float(np.mean(s1 ** 2) ** 2 / np.mean(s2) ** 2)

    def _splat_weights(self, n: int) -> np.ndarray:
        """(n, 2 reach + 1) a splatted sample's weights along one axis toward the pixels within reach (offsets
        -reach .. reach), for n positions spread evenly over its pixel (the midpoint rule)."""
        reach = max(0, int(np.ceil(np.float32(self.radius) - np.float32(0.5))))
        u = (np.arange(n) + 0.5) / n
        x = np.arange(-reach, reach + 1)[None, :] + 0.5 - u[:, None]
        return np.where(np.abs(x) <= self.radius, self.eval(x), 0.0)

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
