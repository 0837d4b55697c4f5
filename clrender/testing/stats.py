"""Statistical comparisons of renders: a film against an analytic value, and two films pixel by pixel.

A film keeps per pixel the sum of w·L, of w and of (w·L)², and the sample count, so each pixel's estimate
comes with the variance of its mean (`Film.variance`). With hundreds of samples per pixel the estimate is
close to normal and a z-test is accurate; the significance level is Šidák-corrected over every pixel and
channel tested, so a single test decides for the whole image.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .chi2 import sidak


@dataclass
class ZTestResult:
    passed: bool
    p_min: float
    alpha: float
    worst: tuple
    message: str


def _ztest(diff, var, alpha, label):
    from scipy import stats

    diff = np.asarray(diff, np.float64)
    var = np.asarray(var, np.float64)
    tested = var > 0
    exact = ~tested
    # Where both sides are exact (zero variance), they must agree to float precision.
    bad_exact = exact & (np.abs(diff) > 1e-5 * np.maximum(1.0, np.abs(diff)))
    n = int(tested.sum())
    a = sidak(alpha, max(n, 1))
    z = np.zeros_like(diff)
    z[tested] = diff[tested] / np.sqrt(var[tested])
    p = np.ones_like(diff)
    p[tested] = 2 * stats.norm.sf(np.abs(z[tested]))
    k = np.unravel_index(int(np.argmin(p)), p.shape)
    p_min = float(p[k])
    if bad_exact.any():
        j = np.unravel_index(int(np.flatnonzero(bad_exact.ravel())[0]), diff.shape)
        return ZTestResult(False, 0.0, a, j, f"{label}: zero-variance values differ at {j}: diff {diff[j]:.4g}")
    ok = p_min >= a
    msg = (f"{label}: {n} values tested, worst z = {z[k]:.2f} at {k} (p = {p_min:.3g}, "
           f"significance {a:.3g})")
    return ZTestResult(ok, p_min, a, k, msg)


def compare_to_value(film, reference, alpha: float = 0.01, mask=None) -> ZTestResult:
    """Each pixel's estimate against the reference (a scalar, RGB triple or (H, W, 3) image)."""
    img = film.image.astype(np.float64)
    ref = np.broadcast_to(np.asarray(reference, np.float64), img.shape)
    var = film.variance()
    if mask is not None:
        img, ref, var = img[mask], ref[mask], var[mask]
    return _ztest(img - ref, var, alpha, "film vs reference")


def compare_to_reference(film, mean, stderr, alpha: float = 0.01, mask=None,
                         ref_samples: int | None = None) -> ZTestResult:
    """Each pixel's estimate against an independent reference image with its own per-pixel standard error
    (e.g. a Mitsuba render): both errors combined.

    With ``ref_samples`` (the reference's samples per pixel) the film's variance is taken to be at least what the
    reference's per-sample variance gives at the film's sample count: a pixel whose rare bright paths the film
    happened not to sample (a penumbra, a caustic) has a sample variance far below its true error, and a test
    that trusted it would fail on noise. A biased pixel still fails, since its difference does not shrink."""
    diff = film.image.astype(np.float64) - np.asarray(mean, np.float64)
    ref_var = np.asarray(stderr, np.float64) ** 2
    film_var = film.variance()
    if ref_samples is not None:
        n = np.maximum(film.count, 1)[..., None]
        film_var = np.maximum(film_var, ref_var * ref_samples / n)
    var = film_var + ref_var
    if mask is not None:
        diff, var = diff[mask], var[mask]
    return _ztest(diff, var, alpha, "film vs reference image")


def compare_image_means(film, mean, stderr, ref_samples: int | None = None, alpha: float = 0.01) -> ZTestResult:
    """The film's mean over all pixels (per channel) against a reference image's, with the variances of
    :func:`compare_to_reference` summed over pixels (pixels are independent in a film)."""
    img = film.image.astype(np.float64).reshape(-1, 3)
    ref = np.asarray(mean, np.float64).reshape(-1, 3)
    ref_var = np.asarray(stderr, np.float64).reshape(-1, 3) ** 2
    film_var = film.variance().reshape(-1, 3)
    if ref_samples is not None:
        film_var = np.maximum(film_var, ref_var * ref_samples / np.maximum(film.count, 1).reshape(-1, 1))
    n = len(img)
    return _ztest(img.mean(axis=0) - ref.mean(axis=0), (film_var + ref_var).sum(axis=0) / n ** 2, alpha,
                  "image mean vs reference")


def compare_films(a, b, alpha: float = 0.01, mask=None) -> ZTestResult:
    """Two independent renders of the same scene (e.g. two integrators): equal per pixel?"""
    da, db = a.image.astype(np.float64), b.image.astype(np.float64)
    var = a.variance() + b.variance()
    diff = da - db
    if mask is not None:
        diff, var = diff[mask], var[mask]
    return _ztest(diff, var, alpha, "film vs film")


def mean_and_error(film, mask=None) -> tuple[np.ndarray, np.ndarray]:
    """Mean over pixels (per channel) and its standard error, from the per-pixel variances."""
    img, var = film.image.astype(np.float64), film.variance()
    if mask is not None:
        img, var = img[mask], var[mask]
    img, var = img.reshape(-1, 3), var.reshape(-1, 3)
    return img.mean(axis=0), np.sqrt(var.sum(axis=0)) / len(img)


def compare_mean_to_value(film, reference, alpha: float = 0.01, mask=None) -> ZTestResult:
    """The image's mean (per channel) against a reference, for scenes whose every pixel has the same value:
    pooling the pixels makes the test robust to heavy-tailed per-pixel estimates."""
    m, se = mean_and_error(film, mask)
    ref = np.broadcast_to(np.asarray(reference, np.float64), m.shape)
    return _ztest(m - ref, se * se, alpha, "image mean vs reference")
