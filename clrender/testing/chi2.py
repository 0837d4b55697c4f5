"""Chi-square goodness-of-fit of sampled directions (or 2-D points) against the sampler's own pdf.

The sphere of directions is cut into `res` bins of cos(theta) and `2 res` bins of phi, so every cell has
the same solid angle. Expected counts integrate the pdf over each cell (a midpoint rule on a finer grid,
exact in the measure because d(omega) = d(cos theta) d(phi)); cells with small expectation are pooled (as
Nori and Mitsuba do); the statistic is compared with the chi-square distribution, and the significance level
is Šidák-corrected over the number of tests run together. Any sample in a cell whose expected count is 0
fails the test outright: the sampler produced something its pdf says is impossible.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Chi2Result:
    passed: bool
    p_value: float
    statistic: float
    dof: int
    message: str
    observed: np.ndarray
    expected: np.ndarray


def sidak(alpha: float, n_tests: int) -> float:
    return 1.0 - (1.0 - alpha) ** (1.0 / max(n_tests, 1))


def bin_directions(dirs: np.ndarray, res: int) -> np.ndarray:
    """(res, 2 res) histogram of unit directions over (cos theta, phi)."""
    d = np.asarray(dirs, np.float64)
    z = np.clip(d[:, 2], -1.0, 1.0)
    phi = np.arctan2(d[:, 1], d[:, 0])
    phi = np.where(phi < 0, phi + 2 * np.pi, phi)
    i = np.clip(((z + 1.0) * 0.5 * res).astype(np.int64), 0, res - 1)
    j = np.clip((phi / (2 * np.pi) * 2 * res).astype(np.int64), 0, 2 * res - 1)
    return np.bincount(i * 2 * res + j, minlength=2 * res * res).reshape(res, 2 * res).astype(np.float64)


def integration_directions(res: int, sub: int = 8) -> tuple[np.ndarray, float]:
    """Midpoints of a (res*sub) x (2 res*sub) grid in (cos theta, phi) as unit vectors, in cell-major
    order so that `expected_from_pdf` can sum each cell's `sub*sub` values; and the solid angle of one point."""
    nz, nphi = res * sub, 2 * res * sub
    z = -1.0 + (np.arange(nz) + 0.5) * (2.0 / nz)
    phi = (np.arange(nphi) + 0.5) * (2 * np.pi / nphi)
    Z, P = np.meshgrid(z, phi, indexing="ij")
    r = np.sqrt(np.maximum(0.0, 1.0 - Z * Z))
    dirs = np.stack([r * np.cos(P), r * np.sin(P), Z], axis=-1)
    return dirs.reshape(-1, 3), (2.0 / nz) * (2 * np.pi / nphi)


def expected_from_pdf(pdf_values: np.ndarray, res: int, sub: int, n_samples: int) -> np.ndarray:
    """Expected counts per cell from pdf values at `integration_directions(res, sub)`."""
    dw = (2.0 / (res * sub)) * (2 * np.pi / (2 * res * sub))
    v = np.asarray(pdf_values, np.float64).reshape(res, sub, 2 * res, sub)
    return v.sum(axis=(1, 3)) * dw * n_samples


def chi2_test(observed: np.ndarray, expected: np.ndarray, min_exp: float = 5.0, alpha: float = 0.01,
              n_tests: int = 1) -> Chi2Result:
    from scipy import stats

    obs = np.asarray(observed, np.float64).ravel()
    exp = np.asarray(expected, np.float64).ravel()
    impossible = (exp <= 0) & (obs > 0)
    if impossible.any():
        k = int(np.flatnonzero(impossible)[0])
        return Chi2Result(False, 0.0, np.inf, 0,
                          f"{int(obs[impossible].sum())} sample(s) fell in cells where the pdf is zero "
                          f"(first: cell {k}, observed {obs[k]:.0f})", observed, expected)
    order = np.argsort(exp)
    pooled_obs = pooled_exp = 0.0
    chsq = 0.0
    dof = 0
    for k in order:
        if exp[k] <= 0:
            continue
        if exp[k] < min_exp:
            pooled_obs += obs[k]
            pooled_exp += exp[k]
        else:
            chsq += (obs[k] - exp[k]) ** 2 / exp[k]
            dof += 1
    if pooled_exp > 0:
        if pooled_exp < min_exp and dof > 0:
            # Too little to stand alone: fold the pool into the smallest regular cell.
            k = next(k for k in order if exp[k] >= min_exp)
            chsq -= (obs[k] - exp[k]) ** 2 / exp[k]
            o, e = obs[k] + pooled_obs, exp[k] + pooled_exp
            chsq += (o - e) ** 2 / e
        else:
            chsq += (pooled_obs - pooled_exp) ** 2 / pooled_exp
            dof += 1
    dof -= 1
    if dof < 1:
        return Chi2Result(True, 1.0, chsq, dof, "too few cells for a chi-square test (trivially passed)",
                          observed, expected)
    p = float(stats.chi2.sf(chsq, dof))
    a = sidak(alpha, n_tests)
    total_o, total_e = obs.sum(), exp.sum()
    ok = p >= a
    msg = (f"chi2 = {chsq:.1f}, dof = {dof}, p = {p:.4g} (significance {a:.3g}); "
           f"sampled {total_o:.0f}, pdf integrates to {total_e / max(total_o, 1):.4f}")
    return Chi2Result(ok, p, chsq, dof, msg, observed, expected)


# ------------------------------------------------------------------------------------------------------
# Integration on partitions refined around peaks. The cells stay Nori's (res cos(theta) bins x 2 res phi
# bins), but the midpoint rule runs on a tensor partition of (cos theta, phi) that contains every cell edge
# and is refined near given peak directions, so narrow lobes (Beckmann alpha = 0.01) integrate accurately
# without a uniformly enormous grid. Each sub-rectangle lies in exactly one cell.

def _partition(edges: np.ndarray, sub: int, extra: np.ndarray) -> np.ndarray:
    fine = [np.linspace(a, b, sub + 1) for a, b in zip(edges[:-1], edges[1:])]
    nodes = np.unique(np.concatenate(fine + [extra[(extra > edges[0]) & (extra < edges[-1])]]))
    return nodes


def refined_direction_grid(res: int, sub: int = 8, peaks=(), n_fine: int = 400, max_points: int | None = None):
    """Integration points for the (res, 2 res) direction cells.

    `peaks`: (direction, angular half-width) pairs; around each, n_fine extra nodes in theta (uniform in
    angle, so fine near the poles too) and in phi (over width / sin(theta), at most the whole circle).
    `max_points`: where the tensor partition would hold more points (many wide peaks: it grows with the square
    of their number), n_fine shrinks until it does not.
    Returns (dirs (N,3), weights = solid angle of each point's sub-rectangle (N,), cell index (N,))."""
    z_edges = np.linspace(-1.0, 1.0, res + 1)
    p_edges = np.linspace(0.0, 2 * np.pi, 2 * res + 1)

    def nodes(n_fine):
        z_extra, p_extra = [np.empty(0)], [np.empty(0)]
        for d, width in peaks:
            d = np.asarray(d, np.float64)
            d = d / np.linalg.norm(d)
            th = np.arccos(np.clip(d[2], -1, 1))
            ths = np.linspace(max(th - width, 0.0), min(th + width, np.pi), n_fine)
            z_extra.append(np.cos(ths))
            s_lo = np.sin(max(th - width, 0.0))
            s_hi = np.sin(min(th + width, np.pi))
            span = min(width / max(min(s_lo, s_hi), 1e-9), np.pi)
            ph = np.arctan2(d[1], d[0])
            p_extra.append(np.mod(ph + np.linspace(-span, span, n_fine), 2 * np.pi))
        return _partition(z_edges, sub, np.concatenate(z_extra)), _partition(p_edges, sub, np.concatenate(p_extra))

    zn, pn = nodes(n_fine)
    while max_points is not None and len(zn) * len(pn) > max_points and n_fine > 2:
        n_fine = max(2, int(n_fine * 0.9 * np.sqrt(max_points / (len(zn) * len(pn)))))
        zn, pn = nodes(n_fine)
    zm, dz = 0.5 * (zn[1:] + zn[:-1]), np.diff(zn)
    pm, dp = 0.5 * (pn[1:] + pn[:-1]), np.diff(pn)
    zi = np.clip(((zm + 1.0) * 0.5 * res).astype(np.int64), 0, res - 1)
    pj = np.clip((pm / (2 * np.pi) * 2 * res).astype(np.int64), 0, 2 * res - 1)
    Z, P = np.meshgrid(zm, pm, indexing="ij")
    r = np.sqrt(np.maximum(0.0, 1.0 - Z * Z))
    dirs = np.stack([r * np.cos(P), r * np.sin(P), Z], axis=-1).reshape(-1, 3)
    weights = np.outer(dz, dp).ravel()
    cell = (zi[:, None] * 2 * res + pj[None, :]).ravel()
    return dirs, weights, cell


def expected_from_grid(pdf_values, weights, cell, shape, n_samples: int) -> np.ndarray:
    """Expected counts per cell (array of `shape`) from pdf values at a grid's points."""
    v = np.asarray(pdf_values, np.float64) * weights
    return np.bincount(cell, weights=v, minlength=int(np.prod(shape))).reshape(shape) * n_samples


def bin_points_2d(points: np.ndarray, lo, hi, res: int) -> np.ndarray:
    """(res, res) histogram of 2-D points over the rectangle [lo, hi]; points outside are put in an
    extra overflow count returned as the last element of a flattened (res*res + 1) array."""
    p = np.asarray(points, np.float64)
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    t = (p - lo) / (hi - lo)
    inside = np.all((t >= 0) & (t <= 1), axis=1)
    ij = np.clip((t * res).astype(np.int64), 0, res - 1)
    k = np.where(inside, ij[:, 0] * res + ij[:, 1], res * res)
    return np.bincount(k, minlength=res * res + 1).astype(np.float64)


def integration_points_2d(lo, hi, res: int, sub: int = 32, seed: int = 1):
    """Stratified jittered points (sub x sub per cell, one per stratum) over [lo, hi]: unbiased for
    densities with edges inside cells (disk, triangle), where a midpoint rule is biased by O(1/sub).
    Returns (points (N,2), weights = area per point, cell index (N,))."""
    rng = np.random.default_rng(seed)
    lo, hi = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    m = res * sub
    I, J = np.meshgrid(np.arange(m), np.arange(m), indexing="ij")
    u = (I + rng.random(I.shape)) / m
    v = (J + rng.random(J.shape)) / m
    pts = np.stack([lo[0] + u * (hi[0] - lo[0]), lo[1] + v * (hi[1] - lo[1])], axis=-1).reshape(-1, 2)
    cell = ((I // sub) * res + (J // sub)).ravel()
    w = np.full(len(pts), np.prod(hi - lo) / (m * m))
    return pts, w, cell


def check_pdf_integral(total_expected: float, keep: np.ndarray, label: str = "", tol: float = 3e-3) -> float:
    """A BSDF's pdf, integrated over the sphere (`total_expected`: the chi-square's expected counts summed, for
    len(keep) samples), must equal the fraction of samples that survive (`keep`), at most 1: what sampling loses
    (visible normals scattered below the horizon or onto the wrong side) its pdf must not claim. A binomial bound
    of 5 sigma plus the quadrature's error `tol` (0.3 %). Returns the surviving fraction."""
    n = len(keep)
    integral, kept = total_expected / n, float(np.mean(keep))
    assert integral <= 1.0 + tol, f"{label}: pdf integrates to {integral:.5f} > 1"
    sigma = np.sqrt(max(kept * (1 - kept), 1e-6) / n)
    assert abs(integral - kept) < 5 * sigma + tol, f"{label}: pdf integrates to {integral:.5f}, kept {kept:.5f}"
    return kept


def check_sample_weights(s, keep: np.ndarray, wi: np.ndarray) -> np.ndarray:
    """Every kept sample of a smooth BSDF (batch `s` of testing.kernels.bsdf_sample_batch) has weight f cos / pdf,
    and an eta of 1 where it reflects. Returns which kept samples reflect (the rest transmit)."""
    assert np.all(s.measure == 0) and np.all(np.isfinite(s.weight))
    w, f, pdf, cos = s.weight[keep], s.f[keep], s.pdf[keep], np.abs(s.wo[keep, 2])
    assert np.all(pdf > 0) and np.all(cos > 0)
    np.testing.assert_allclose(w, f * (cos / pdf)[:, None], rtol=2e-4, atol=1e-7)
    refl = s.wo[keep, 2] * wi[2] > 0
    assert np.all(s.eta[keep][refl] == 1)
    return refl
