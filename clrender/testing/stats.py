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


#: relative agreement expected of two float32 renderers on a noiseless pixel (compare_to_reference)
FLOAT_AGREEMENT = 1e-5


def footprint_sample_variance(mean, sample_var, rfilter) -> np.ndarray:
    """The variance of one filter-importance-sampled camera sample of each pixel, predicted from a reference
    image: ``mean`` (H, W, 3) and the variance of one sample within each pixel, ``sample_var``.

    A sample of pixel p lands at an offset drawn with density |f| (kernels/filter.h) and carries sign(f)·C·L,
    C = ∫|f| / ∫f per axis. Taking L within pixel q to have q's mean m_q and variance v_q (the law of total
    variance; the reference is itself filtered, so this is a proxy that understates sharp detail), with a_q the
    share of |f| over pixel q: the variance is C² Σ_q a_q (v_q + m_q²) - (C Σ_q a_q sign_q m_q)². Pixels outside
    the image count as absent (their share is given to the others)."""
    x = (np.arange(8000) + 0.5) / 8000 * 2 * rfilter.radius - rfilter.radius   # midpoints
    f = np.asarray(rfilter.eval(x), np.float64)
    c = np.abs(f).sum() / f.sum()
    k = int(np.ceil(rfilter.radius + 0.5))
    offsets = np.arange(-k, k + 1)
    cells = [(x >= o - 0.5) & (x < o + 0.5) for o in offsets]
    share = np.array([np.abs(f[m]).sum() for m in cells])
    signed = np.array([f[m].sum() for m in cells])
    share, signed = share / share.sum(), signed / np.abs(f).sum()
    mean = np.asarray(mean, np.float64)
    second = np.asarray(sample_var, np.float64) + mean ** 2
    h, w = mean.shape[:2]
    acc2, acc1 = np.zeros_like(mean), np.zeros_like(mean)
    norm = np.zeros(mean.shape[:2] + (1,))
    for i, oy in enumerate(offsets):
        for j, ox in enumerate(offsets):
            a = share[i] * share[j]
            if a == 0:
                continue
            ys, xs = slice(max(0, -oy), min(h, h - oy)), slice(max(0, -ox), min(w, w - ox))
            yq, xq = slice(max(0, oy), min(h, h + oy)), slice(max(0, ox), min(w, w + ox))
            acc2[ys, xs] += a * second[yq, xq]
            acc1[ys, xs] += signed[i] * signed[j] * mean[yq, xq]
            norm[ys, xs] += a
    norm = np.maximum(norm, 1e-300)
    return np.maximum(c * c * acc2 / norm - (c * acc1 / norm) ** 2, 0.0)


def neighbourhood_mean(a: np.ndarray) -> np.ndarray:
    """Each pixel's mean over its 3 x 3 neighbourhood (as far as it lies in the image)."""
    h, w = a.shape[:2]
    total = np.zeros_like(a, dtype=np.float64)
    count = np.zeros((h, w) + (1,) * (a.ndim - 2))
    for oy in (-1, 0, 1):
        for ox in (-1, 0, 1):
            ys, xs = slice(max(0, -oy), min(h, h - oy)), slice(max(0, -ox), min(w, w - ox))
            yq, xq = slice(max(0, oy), min(h, h + oy)), slice(max(0, ox), min(w, w + ox))
            total[ys, xs] += a[yq, xq]
            count[ys, xs] += 1
    return total / count


def _film_variance(film, stderr, ref_samples, ref_mean, rfilter):
    """The film's per-pixel variance, at least what the reference predicts for it and what the film's own
    neighbouring pixels show (see compare_to_reference)."""
    var = film.variance()
    if ref_samples is None:
        return var
    var = np.maximum(var, neighbourhood_mean(var))
    per_sample = np.asarray(stderr, np.float64) ** 2 * ref_samples
    if rfilter is not None:
        per_sample = np.maximum(per_sample, footprint_sample_variance(ref_mean, per_sample, rfilter))
    return np.maximum(var, per_sample / np.maximum(film.count, 1)[..., None])


def compare_to_reference(film, mean, stderr, alpha: float = 0.01, mask=None,
                         ref_samples: int | None = None, rfilter=None) -> ZTestResult:
    """Each pixel's estimate against an independent reference image with its own per-pixel standard error
    (e.g. a Mitsuba render): both errors combined.

    With ``ref_samples`` (the reference's samples per pixel) the film's variance is taken to be at least what the
    reference predicts for the film's sample count: its per-sample variance within the pixel and, given the
    film's reconstruction filter ``rfilter``, the spread of the reference over the filter's footprint
    (:func:`footprint_sample_variance`), and at least the mean variance of its 3 x 3 neighbourhood in the film. A
    pixel whose rare bright paths or rare far filter offsets the film happened not to sample has a sample variance
    far below its true error, and a test trusting it would fail on noise; a biased pixel still fails, since its
    difference does not shrink."""
    diff = film.image.astype(np.float64) - np.asarray(mean, np.float64)
    ref_var = np.asarray(stderr, np.float64) ** 2
    var = _film_variance(film, stderr, ref_samples, mean, rfilter) + ref_var
    # Two float32 renderers agree to about 1e-5 relative where neither has noise (an emitter seen directly).
    var = var + (FLOAT_AGREEMENT * np.asarray(mean, np.float64)) ** 2
    if mask is not None:
        diff, var = diff[mask], var[mask]
    return _ztest(diff, var, alpha, "film vs reference image")


def compare_image_means(film, mean, stderr, ref_samples: int | None = None, alpha: float = 0.01,
                        rfilter=None) -> ZTestResult:
    """The film's mean over all pixels (per channel) against a reference image's, with the variances of
    :func:`compare_to_reference` summed over pixels (independent in a filter-sampling film; a splatting film's
    times pool_factor)."""
    img = film.image.astype(np.float64).reshape(-1, 3)
    ref = np.asarray(mean, np.float64).reshape(-1, 3)
    ref_var = (np.asarray(stderr, np.float64) ** 2).reshape(-1, 3)
    film_var = _film_variance(film, stderr, ref_samples, mean, rfilter).reshape(-1, 3) * pool_factor(film)
    n = len(img)
    return _ztest(img.mean(axis=0) - ref.mean(axis=0), (film_var + ref_var).sum(axis=0) / n ** 2, alpha,
                  "image mean vs reference")


def compare_films(a, b, alpha: float = 0.01, mask=None) -> ZTestResult:
    """Two independent renders of the same scene (e.g. two integrators): equal per pixel? A difference within
    FLOAT_AGREEMENT of the value is rounding, whatever the films' variances say (a splatting film's pixel of
    constant sky: 25 neighbours' float32 sums, variance 1e-15, differences of 1e-6 of the value)."""
    da, db = a.image.astype(np.float64), b.image.astype(np.float64)
    var = a.variance() + b.variance()
    var = np.where(var > 0, var + (FLOAT_AGREEMENT * np.maximum(np.abs(da), np.abs(db))) ** 2, var)
    diff = da - db
    if mask is not None:
        diff, var = diff[mask], var[mask]
    return _ztest(diff, var, alpha, "film vs film")


def pool_factor(film) -> float:
    """What a sum of a splatting film's pixels' variances is to be multiplied by for the variance of the sum of the
    pixels (neighbours share samples: Filter.splat_pool_factor, recorded by the Renderer; 4 where a merged film
    lost the record, above what the Gaussian, tent and Mitchell filters give); 1 for a filter-sampling film."""
    if getattr(film, "sum_w2", None) is None:
        return 1.0
    return float(film.metadata.get("splat_pool", 4.0))


def mean_and_error(film, mask=None) -> tuple[np.ndarray, np.ndarray]:
    """Mean over pixels (per channel) and its standard error, from the per-pixel variances (and pool_factor)."""
    img, var = film.image.astype(np.float64), film.variance() * pool_factor(film)
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



def block_sums(image: np.ndarray, block: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """Sums of the image over block x block tiles (the last row and column of tiles may be smaller), and the
    number of pixels in each tile: (ceil(H / block), ceil(W / block)) + image.shape[2:], and (ceil(H / block),
    ceil(W / block))."""
    a = np.asarray(image, np.float64)
    h, w = a.shape[:2]
    ys, xs = range(0, h, block), range(0, w, block)
    sums = np.stack([np.stack([a[y:y + block, x:x + block].sum(axis=(0, 1)) for x in xs]) for y in ys])
    counts = np.array([[min(block, h - y) * min(block, w - x) for x in xs] for y in ys], np.float64)
    return sums, counts


def compare_block_means_to_value(film, reference, block: int = 16, alpha: float = 0.01) -> ZTestResult:
    """Each block x block tile's mean (per channel) against a reference value, for scenes whose every pixel has
    the same value: local like a per-pixel test (a leak along one edge fails it) but pooling a tile's samples, so
    the means are close to normal where a pixel's few samples are skewed (Russian roulette, small bright lights)."""
    sums, n = block_sums(film.image, block)
    var, _ = block_sums(film.variance() * pool_factor(film), block)
    n = n.reshape(n.shape + (1,) * (sums.ndim - 2))
    m = sums / n
    ref = np.broadcast_to(np.asarray(reference, np.float64), m.shape)
    return _ztest(m - ref, var / (n * n), alpha, f"{block}x{block} block means vs reference")
