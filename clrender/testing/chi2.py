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
