"""Chi-square of every warp in kernels/warp.h against its own density, both run on the device.

2-D warps are binned on a res x res grid over their domain (expected counts by stratified jittered
integration, unbiased where the density has an edge inside a cell); directional ones on Nori's
(cos theta, phi) sphere cells. One Šidák correction over the whole set.
"""
import numpy as np
import pytest

from clrender.testing.chi2 import (bin_directions, bin_points_2d, chi2_test, expected_from_grid,
                                   integration_points_2d, refined_direction_grid)
from clrender.testing.kernels import warp_pdf_batch, warp_sample_batch

ALPHA = 0.01
N = 1_000_000

# name, warp, param, kind ("2d" with its domain, or "dir" with res and peak refinement)
CASES = [
    ("square", "square", 0.0, ("2d", (0, 0), (1, 1))),
    ("tent", "tent", 0.0, ("2d", (-1, -1), (1, 1))),
    ("disk", "disk", 0.0, ("2d", (-1, -1), (1, 1))),
    ("triangle", "triangle", 0.0, ("2d", (0, 0), (1, 1))),
    ("sphere", "sphere", 0.0, ("dir", 10, None)),
    ("hemisphere", "hemisphere", 0.0, ("dir", 10, None)),
    ("cosine_hemisphere", "cosine_hemisphere", 0.0, ("dir", 10, None)),
    # cone edges at cos 0.5 and 0.85 fall inside cells; the theta refinement puts nodes next to them
    ("cone-60deg", "cone", 0.5, ("dir", 10, 0.5)),
    ("cone-32deg", "cone", 0.85, ("dir", 20, 0.85)),
    ("beckmann-0.05", "beckmann", 0.05, ("dir", 10, "beck")),
    ("beckmann-0.3", "beckmann", 0.3, ("dir", 10, "beck")),
    ("beckmann-1.0", "beckmann", 1.0, ("dir", 10, "beck")),
]
RES_2D = 20


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_warp_chi2(ctx, queue, case):
    name, warp, param, kind = case
    pts = warp_sample_batch(ctx, queue, warp, N, param, seed=17)
    assert np.all(np.isfinite(pts))
    if kind[0] == "2d":
        lo, hi = kind[1], kind[2]
        counts = bin_points_2d(pts, lo, hi, RES_2D)
        assert counts[-1] == 0, f"{int(counts[-1])} samples outside the domain"
        obs = counts[:-1].reshape(RES_2D, RES_2D)
        gp, w, cell = integration_points_2d(lo, hi, RES_2D, sub=32)
        pdf = warp_pdf_batch(ctx, queue, warp, gp, param)
        exp = expected_from_grid(pdf, w, cell, (RES_2D, RES_2D), N)
    else:
        res, extra = kind[1], kind[2]
        np.testing.assert_allclose(np.linalg.norm(pts, axis=1), 1, atol=2e-6)
        obs = bin_directions(pts, res)
        peaks = []
        if extra == "beck":
            peaks = [((0, 0, 1), min(6 * param, np.pi / 2))]
        elif extra is not None:
            # a band of nodes around the cone's edge (theta = acos(cos_max)), so the edge is resolved
            th = np.arccos(extra)
            peaks = [((np.sin(th), 0, np.cos(th)), 0.02)]
        dirs, w, cell = refined_direction_grid(res, 8, peaks, n_fine=400)
        pdf = warp_pdf_batch(ctx, queue, warp, dirs, param)
        exp = expected_from_grid(pdf, w, cell, (res, 2 * res), N)
    r = chi2_test(obs, exp, min_exp=5.0, alpha=ALPHA, n_tests=len(CASES))
    assert r.passed, f"{name}: {r.message}"
    assert abs(exp.sum() / N - 1) < 2e-3, f"{name}: the density integrates to {exp.sum() / N}"


def test_warp_chi2_rejects_mismatch(ctx, queue):
    """Cosine-hemisphere samples scored against the uniform hemisphere density must fail."""
    pts = warp_sample_batch(ctx, queue, "cosine_hemisphere", N, 0.0, seed=5)
    obs = bin_directions(pts, 10)
    dirs, w, cell = refined_direction_grid(10, 8)
    pdf = warp_pdf_batch(ctx, queue, "hemisphere", dirs)
    exp = expected_from_grid(pdf, w, cell, (10, 20), N)
    assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=len(CASES)).passed
    # and tent samples against the uniform square density on [-1,1]^2
    pts = warp_sample_batch(ctx, queue, "tent", N, 0.0, seed=5)
    counts = bin_points_2d(pts, (-1, -1), (1, 1), RES_2D)
    gp, w, cell = integration_points_2d((-1, -1), (1, 1), RES_2D, sub=8)
    exp = expected_from_grid(np.full(len(gp), 0.25), w, cell, (RES_2D, RES_2D), N)
    assert not chi2_test(counts[:-1], exp, alpha=ALPHA, n_tests=len(CASES)).passed
