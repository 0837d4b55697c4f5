"""`clrender warptest WARP [PARAM]`: chi-square test of one warping function against its own density.

2-D warps (square, tent, disk, triangle) are binned on their domain; directional ones (sphere, hemisphere,
cosine_hemisphere, cone, beckmann) on the sphere in (cos θ, φ) cells of equal solid angle. PARAM is the
cone's half-angle in degrees or Beckmann's alpha. The observed and expected histograms are saved as a PNG.
"""
from __future__ import annotations

import math

import numpy as np

from .chi2 import (bin_directions, bin_points_2d, chi2_test, expected_from_grid, integration_points_2d,
                   refined_direction_grid)
from .kernels import WARPS, warp_pdf_batch, warp_sample_batch

DOMAINS = {"square": ((0, 0), (1, 1)), "tent": ((-1, -1), (1, 1)), "disk": ((-1, -1), (1, 1)),
           "triangle": ((0, 0), (1, 1))}
DEFAULT_PARAM = {"cone": 30.0, "beckmann": 0.3}


def run_warptest(warp: str, param: float | None = None, samples: int = 1_000_000, res: int = 20,
                 device=None, seed: int = 0, alpha: float = 0.01):
    from ..device.context import get_context

    if warp not in WARPS:
        raise ValueError(f"unknown warp '{warp}'; known: {', '.join(WARPS)}")
    if not 1 <= samples < 2**31:
        raise ValueError(f"--samples must be between 1 and {2**31 - 1}, got {samples}")
    if param is not None:
        if warp not in DEFAULT_PARAM:
            raise ValueError(f"warp '{warp}' takes no parameter (got {param:g}); only cone and beckmann do")
        if warp == "cone" and not 0 < param <= 180:
            raise ValueError(f"the cone's half-angle must be in (0, 180] degrees, got {param:g}")
        if warp == "beckmann" and not 0 < param <= 10:
            raise ValueError(f"Beckmann's alpha must be in (0, 10], got {param:g}")
    ctx, queue = get_context(device)
    p = DEFAULT_PARAM.get(warp, 0.0) if param is None else float(param)
    kparam = math.cos(math.radians(p)) if warp == "cone" else p
    pts = warp_sample_batch(ctx, queue, warp, samples, kparam, seed)
    if warp in DOMAINS:
        lo, hi = DOMAINS[warp]
        counts = bin_points_2d(pts, lo, hi, res)
        grid, w, cell = integration_points_2d(lo, hi, res)
        pdf = warp_pdf_batch(ctx, queue, warp, grid, kparam)
        expected = np.append(expected_from_grid(pdf, w, cell, (res, res), samples).ravel(), 0.0)
        observed = counts
        shape = None
    else:
        r = max(4, res // 2)
        observed = bin_directions(pts, r)
        peaks = [((0, 0, 1), min(math.pi, 12 * p))] if warp == "beckmann" else []
        if warp == "cone":
            peaks = [((0, 0, 1), math.radians(p) + 0.05)]
        dirs, w, cell = refined_direction_grid(r, 8, peaks, 200 if peaks else 0)
        pdf = warp_pdf_batch(ctx, queue, warp, dirs, kparam)
        expected = expected_from_grid(pdf, w, cell, (r, 2 * r), samples)
        shape = (r, 2 * r)
    result = chi2_test(observed, expected, alpha=alpha)
    if shape is None:
        obs_img, exp_img = observed[:-1].reshape(res, res), expected[:-1].reshape(res, res)
    else:
        obs_img, exp_img = observed.reshape(shape), expected.reshape(shape)
    return result, obs_img, exp_img, p
