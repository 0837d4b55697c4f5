"""Adaptive sampling to a target error: render in rounds, each over only the pixels whose estimate is not yet good
enough, until every pixel meets the target, at `max_spp`, at the time limit or at Ctrl-C.

A pixel is tested only at fixed sample counts (`checkpoints`: `min_spp`, then a quarter more each, up to
`max_spp`), the same for every pixel and every run. The first round takes every pixel to `min_spp`; after each
round, a pixel that failed its test goes on to the checkpoint its pooled error predicts it needs (next_counts: the
error falls as 1/sqrt(n)), at least the next one and at most twice its samples, all in the next round's one launch
(kernels/render.cl render_spans, or kernels/splat.cl store_spans on the splatting film, whose store keeps each
pixel's splats apart and weighs them by 1 / its count when the film is read: each listed pixel with its own first
sample and count; without it, the wavefront and the feature AOVs' pass, one list launch per distinct span). So a render needs a handful of rounds instead of one
per checkpoint: each round costs 10-20 ms of fixed work (the film's download, the test, the launch and its wait) and
the late ones, over a few hundred pixels, leave cores idle. A pixel's samples are numbered 0, 1, 2, ... as in a
uniform render (its n samples are those a uniform render of n spp gives it), and its sums depend only on its own
samples and the spans it got them in, never on how the list is cut into launches, on the executor's wave size or
on timing. So whether a pixel goes on after a round is a function of its own (and its neighbours') samples, and the
same seed and options give the same image and the same per-pixel counts however the work is split
(tests/test_adaptive.py). A time limit or Ctrl-C stops between launches; the image keeps its true per-pixel counts
(``film.count``, the EXR's ``count`` layer).

The stopping rule, per pixel after each round, is a confidence test: the pixel has converged when, with 95 %
confidence in its sample variance, the standard error of its estimate is within `target_error` of its value in
every channel, values below 0.1 counting as 0.1 (so the error is the one relMSE's 1e-2 measures: dark pixels do
not take every sample chasing a relative error of nothing). The variance's upper confidence limit,
s^2 (n - 1) / chi2_0.05(n - 1), is about 2 s^2 at 16 samples and 1.15 s^2 at 256: a few lucky low-variance samples
do not stop a pixel early. And the test pools the squared error of the pixel and its 8 neighbours (noise is spatially
coherent: a pixel whose neighbours still see a caustic may have missed it by chance, as Cycles' filtered
convergence mask assumes). Pooling matters for bias, not only for caution: a pixel's own lucky run of samples is
both low in variance and, for the skewed estimates of path tracing, low in value, so stopping on its own variance
alone stops the low estimates early (measured in a furnace: pixels 4 standard errors low); pooled, a pixel's own
samples weigh 1/9 in its decision. A pixel that has stopped stays stopped.

Where the noise is even, adaptive allocation cannot win: its samples go where uniform sampling's would, and its
rounds cost time (measured 10-30 % slower than uniform on the diffuse Cornell box and our Veach MIS scene). So after
a first round of at least 16 samples the render measures the potential gain of any allocation over uniform
sampling (predicted_allocation: mean(a) / mean(sqrt a)^2 of the pixels' relative variances per sample) and, below
`uniform_below` (UNIFORM_BELOW), finishes as a uniform render: every pixel on to the spp the stopping rule is
expected to spend on average, in rounds over ranges and without tests, so it costs what a uniform render costs. The
decision depends only on the first round's samples, so the image stays deterministic; it is the uniform render's
image at that spp (metadata ``uniform_after``, ``uniform_spp``, ``predicted_gain``). Such an image has about the
relMSE the allocation would have reached, not every pixel within the target (``converged`` says how many are).
"""
from __future__ import annotations

import copy
import sys
import time
from dataclasses import dataclass

import numpy as np

from .executors import LOCAL_SIZE, TARGET_LAUNCH_SECONDS
from .interrupt import wait_for

#: relMSE's denominator term (clrender/bench.py relmse): values below its square root count as that much
RELMSE_EPS = 1e-2
#: confidence of the variance bound in the stopping test
CONFIDENCE = 0.95
#: the number of samples a round adds grows with the samples so far by this fraction (at least min_spp)
ROUND_GROWTH = 0.25


#: after the first round, below this potential gain (mean(a) / mean(sqrt a)^2 over the noisy pixels: the samples
#: ratio of the best allocation over uniform sampling) the render finishes as a uniform one (predicted_allocation)
UNIFORM_BELOW = 1.3
#: ... decided only after a first round of at least this many samples: fewer hide the spread (the test Cornell box,
#: 1.39-1.44 from 16 samples, looks 1.19 from 4)
SWITCH_MIN_SPP = 16

#: after the first round a pixel's samples at most double from one test to the next: the prediction of its need
#: (next_counts) from 16 samples is a rough one (the variance's confidence bound alone is 2x there)
MAX_ROUND_GROWTH = 2.0

#: how the samples are shared out: "error", every pixel to the target error; "relmse", the least relMSE of the image
ALLOCATIONS = ("error", "relmse")


@dataclass(frozen=True)
class AdaptiveOptions:
    target_error: float
    min_spp: int
    max_spp: int
    allocation: str = "error"
    #: below this potential gain, after the first round, finish as a uniform render (0: never)
    uniform_below: float = UNIFORM_BELOW

    @classmethod
    def make(cls, target_error, min_spp=None, max_spp=None, default_max_spp: int = 64,
             allocation: str = "error", uniform_below: float = UNIFORM_BELOW) -> "AdaptiveOptions":
        """Checked options; `max_spp` defaults to `default_max_spp` (the scene's sample count), `min_spp` to 16
        (at most max_spp); `uniform_below` 0 keeps every render adaptive. Raises ValueError naming the option that
        is wrong."""
        if allocation not in ALLOCATIONS:
            raise ValueError(f"allocation must be one of {', '.join(ALLOCATIONS)}, got {allocation!r}")
        try:
            e = float(target_error)
        except (TypeError, ValueError):
            raise ValueError(f"target error must be a number, got {target_error!r}") from None
        if not (np.isfinite(e) and e > 0):
            raise ValueError(f"target error must be a positive number (a relative error, e.g. 0.01), got {e:g}")
        hi = int(default_max_spp if max_spp is None else max_spp)
        if not 1 <= hi < 2**32:
            raise ValueError(f"max spp must be between 1 and 4294967295, got {hi}")
        lo = min(16, hi) if min_spp is None else int(min_spp)
        if not 2 <= lo <= hi:
            raise ValueError(f"min spp must be at least 2 (a variance needs two samples) and at most max spp "
                             f"({hi}), got {lo}")
        if not (uniform_below >= 0 and np.isfinite(uniform_below)):
            raise ValueError(f"uniform_below must be a finite number >= 0, got {uniform_below}")
        return cls(e, lo, hi, allocation, float(uniform_below))

    def checkpoints(self) -> list[int]:
        """The sample counts at which every still-active pixel is tested."""
        out = [self.min_spp]
        while out[-1] < self.max_spp:
            out.append(min(self.max_spp, out[-1] + max(self.min_spp, int(out[-1] * ROUND_GROWTH))))
        return out


def variance_bound(counts) -> np.ndarray:
    """The factor from a sample variance of `counts` samples to its upper CONFIDENCE limit: (n - 1) / chi2_0.05(n - 1);
    inf below two samples."""
    from scipy.stats import chi2

    # the quantile once per distinct count (chi2.ppf per pixel took 11 % of an adaptive render of a 128 x 128
    # Cornell box, and 10 % of one of the rough plates in predicted_allocation), and once per process: the counts
    # are the checkpoints, and each chi2.ppf call costs about a millisecond, several per round
    counts, inverse = np.unique(np.asarray(counts), return_inverse=True)
    new = [int(c) for c in counts if int(c) not in _BOUNDS]
    if new:
        dof = np.maximum(np.array(new, np.float64) - 1, 1)
        _BOUNDS.update(zip(new, np.where(np.array(new) >= 2, dof / chi2.ppf(1.0 - CONFIDENCE, dof), np.inf)))
    return np.array([_BOUNDS[int(c)] for c in counts], np.float64)[inverse].reshape(np.shape(inverse))


#: variance_bound's factor by sample count, as computed so far
_BOUNDS: dict[int, float] = {}


def relative_error(film) -> np.ndarray:
    """(H, W) the pixel's error as the stopping rule sees it: the largest over channels of the standard error (from
    the variance's upper 95 % confidence limit) over max(|value|, 0.1) in quadrature, i.e.
    sqrt(var_up / (value^2 + 1e-2)). Pixels without two samples: inf."""
    factor = variance_bound(film.count).reshape(film.count.shape)
    img = film.image.astype(np.float64)
    with np.errstate(invalid="ignore"):
        err2 = film.variance() * factor[..., None] / (img * img + RELMSE_EPS)
    err2 = np.where(np.isnan(err2), np.inf, err2)
    return np.sqrt(err2.max(axis=-1))


def pooled_error(film) -> np.ndarray:
    """(H, W) what the stopping rule tests: relative_error's square averaged over the pixel and its 8 neighbours (the
    image's edge repeats its border pixels), square-rooted."""
    return np.sqrt(_pool(np.minimum(relative_error(film) ** 2, 1e12)))   # inf (fewer than two samples): huge


def _pool(x: np.ndarray) -> np.ndarray:
    """The mean of x over each pixel and its 8 neighbours (the image's edge repeats its border pixels)."""
    # nine shifted sums, not scipy's uniform_filter: its running sums lose small errors beside huge ones
    p = np.pad(x, 1, mode="edge")
    h, w = x.shape
    return sum(p[i:i + h, j:j + w] for i in range(3) for j in range(3)) / 9.0


def predicted_allocation(film, opts: "AdaptiveOptions") -> tuple[float, int]:
    """(gain, n): after the first round, the potential gain of adaptive allocation over uniform sampling, and the
    spp a uniform render needs for the relMSE the allocation is expected to reach.

    a_p, the relative variance of one sample of pixel p (relMSE's: channel mean of var / (value^2 + 1e-2)),
    pooled over its 3 x 3 neighbourhood as the stopping rule pools; the allocation's expected samples n_p: where
    a_p / n_p meets the rule's bound (E^2 for "error", E^2 n_p / min_spp for "relmse"), within min_spp..max_spp.
    Uniform sampling with the same mean of samples N leaves a relMSE of mean(a) / N against the allocation's
    mean(a / n), so mean(a) / mean(a / n) spp give uniform the same relMSE. The gain is that of the best
    allocation, n_p ~ sqrt(a_p): mean(a) / mean(sqrt a)^2 (Cauchy-Schwarz), whatever the allocation asked for. Not
    the expected allocation's own gain: a_p from min_spp samples misses the rare bright paths (caustics through
    glass) that later rounds find, so that figure comes out near 1 where adaptive sampling measurably wins 2x,
    whereas the spread of sqrt(a) already separates the scenes: 1.13-1.21 on the diffuse Cornell box and our Veach
    MIS scene (where adaptive sampling lost 10-30 % of the time), 1.01 in the furnace, 1.46 with the glass spheres
    and 4.2 on the rough plates (where it won 2.2-2.6x) at 16 spp (benchmarks/README.md).
    Over the pixels whose samples vary: an exact pixel (background, a light seen directly) is cheap and needs no
    samples either way, and counting it would credit adaptive sampling with savings that cost no time (in the
    furnace, 1.7x fewer samples bought nothing)."""
    n0 = film.count.astype(np.float64)
    a_rgb = film.variance() * n0[..., None] / (film.image.astype(np.float64) ** 2 + RELMSE_EPS)
    noisy = a_rgb.mean(axis=-1) > 0
    if not noisy.any():
        return 1.0, int(film.count.max())
    a = _pool(a_rgb.mean(axis=-1))[noisy]
    # the rule's samples: its test takes the largest channel and the variance's confidence bound, at about n
    a_test = _pool(a_rgb.max(axis=-1))[noisy]
    e2 = opts.target_error ** 2
    n = np.full(a.shape, float(opts.min_spp))
    for _ in range(2):   # the bound's factor at the samples the last step gave (1.15-2: two steps settle it)
        b = a_test * variance_bound(np.ceil(n).astype(np.int64))
        n = np.sqrt(b * opts.min_spp / e2) if opts.allocation == "relmse" else b / e2
        n = np.clip(n, opts.min_spp, opts.max_spp)
    per_sample = float(np.mean(a / n))
    gain = float(a.mean() / np.sqrt(a).mean() ** 2)
    return gain, int(np.clip(np.ceil(a.mean() / per_sample), opts.min_spp, opts.max_spp))


def pooled_error_at(film, pixels: np.ndarray) -> np.ndarray:
    """pooled_error at the flat pixel indices `pixels` only, the very same values: the rounds near the end test a
    few hundred pixels, and the whole image's test cost each round more than its launch (15 % of an adaptive
    render of the rough plates)."""
    return _pooled(_pooled_terms(film, pixels)[0])


def _pooled_terms(film, pixels: np.ndarray):
    """((m, 9) squared relative errors of each of `pixels`' 3 x 3 neighbours in pooled_error's order, clamped at
    the border as its edge padding repeats it; (m, 9) their flat indices), from the whole image's errors or, for
    fewer than an eighth of the pixels, from those of their neighbourhoods alone."""
    from .film import Film

    h, w = film.count.shape
    y, x = np.divmod(np.asarray(pixels, np.int64), w)
    nb = np.stack([np.clip(y + i - 1, 0, h - 1) * w + np.clip(x + j - 1, 0, w - 1)
                   for i in range(3) for j in range(3)], axis=-1)
    if len(nb) * 8 >= h * w:
        return np.minimum(relative_error(film) ** 2, 1e12).reshape(-1)[nb], nb
    at, inverse = np.unique(nb, return_inverse=True)
    flat = lambda a: a.reshape(h * w, *a.shape[2:])[at][None]  # noqa: E731  (a one-row film of those pixels)
    sub = Film(len(at), 1, flat(film.sum_wl), flat(film.sum_w), flat(film.sum_wl2), flat(film.count),
               flat(film.dropped))
    return np.minimum(relative_error(sub)[0] ** 2, 1e12)[inverse.reshape(nb.shape)], nb


def _pooled(terms: np.ndarray) -> np.ndarray:
    return np.sqrt(sum(terms[:, k] for k in range(9)) / 9.0)   # summed in pooled_error's order: equal bits


def converged(film, target_error: float, allocation: str = "error", min_spp: int = 16) -> np.ndarray:
    """(H, W) bool: the pixel's pooled error meets the target: `target_error` itself ("error"), or, for the least
    relMSE of the whole image for its samples ("relmse"), target_error * sqrt(n / min_spp) for a pixel of n samples.

    Why the second: with a_p the relative variance of one sample of pixel p, n_p samples leave it an error a_p / n_p;
    for a given total of samples the image's mean is least at n_p ~ sqrt(a_p) (Lagrange; Cauchy-Schwarz gives the gain
    over uniform sampling, mean(a) / mean(sqrt a)^2), whereas equal errors (n_p ~ a_p) give the very mean relMSE of
    uniform sampling, gaining only where pixels converge for free. n_p ~ sqrt(a_p) is where a_p / n_p <= c n_p, i.e.
    the error falls below a bound growing as sqrt(n_p): noisy pixels get more samples, not all they would need."""
    bound = target_error
    if allocation == "relmse":
        bound = target_error * np.sqrt(np.maximum(film.count, 1) / float(min_spp))
    return pooled_error(film) <= bound


def next_counts(counts, scaling, frozen, opts: "AdaptiveOptions", marks=None) -> np.ndarray:
    """The sample count at which each pixel that failed its test at `counts` samples is tested next: the checkpoint
    at or above the count its pooled error predicts, at least the next checkpoint and at most MAX_ROUND_GROWTH times
    `counts` (where that is a checkpoint beyond the next).

    The pooled error squared is `scaling` + `frozen`: the share (of the 3 x 3 mean) of the neighbours that go on
    with the pixel, and of those that have stopped, whose errors stay. The first falls as 1/n times the variance
    bound's factor vb (2 at 16 samples, 1.15 at 256) as they get samples: the model at n samples is
    F + S (c / n) vb(n) / vb(c), and the pixel goes to the first candidate checkpoint where the model meets the
    allocation's bound (E^2, or E^2 n / min_spp for "relmse"), or to the last (the cap: where the stopped neighbours
    alone miss the bound, it goes on to max_spp anyway). Without the frozen share, pixels beside stopped ones missed
    their target by a few per cent at every checkpoint on the rough plates: ten rounds more."""
    marks = np.asarray(opts.checkpoints() if marks is None else marks, np.int64)
    c = np.asarray(counts, np.int64)
    S, F = np.asarray(scaling, np.float64), np.asarray(frozen, np.float64)
    i_lo = np.minimum(np.searchsorted(marks, c, side="right"), len(marks) - 1)   # the next checkpoint
    i_hi = np.maximum(np.searchsorted(marks, MAX_ROUND_GROWTH * c, side="right") - 1, i_lo)
    choice = i_hi.copy()
    vb_c = variance_bound(c)
    for j in range(int((i_hi - i_lo).max(initial=0)), -1, -1):   # the candidates, down: the least that meets wins
        i = np.minimum(i_lo + j, i_hi)
        n = marks[i]
        meets = F + S * c / n * variance_bound(n) / vb_c <= _bound(n, opts) ** 2
        choice = np.where(meets, i, choice)
    return marks[choice]


def _bound(counts, opts: "AdaptiveOptions"):
    """The pooled error a pixel of `counts` samples must meet (converged's bound)."""
    if opts.allocation == "relmse":
        return opts.target_error * np.sqrt(np.maximum(counts, 1) / float(opts.min_spp))
    return np.full(np.shape(counts), opts.target_error)


def render_adaptive(renderer, opts: AdaptiveOptions, seed: int = 0, time_limit: float | None = None,
                    progress: bool = False, partial=None, on_round=None):
    """The adaptive render of `renderer`'s scene (see the module's docstring); returns its Film, whose ``count``
    holds each pixel's samples and whose metadata adds ``adaptive``, ``target_error``, ``min_spp``, ``max_spp``,
    ``spp_mean``, ``converged`` (the fraction of pixels that met the target) and ``rounds``. ``partial`` as
    Renderer.render's; ``on_round(round, samples, n_pixels)`` is called before each round (`samples`: the most
    any of its pixels goes to)."""
    import pyopencl as cl

    from .interrupt import PassFlag as _SigintFlag

    if time_limit is not None and not (time_limit > 0 and np.isfinite(time_limit)):
        raise ValueError(f"time_limit must be a positive finite number of seconds, got {time_limit}")
    r = renderer
    n = r.n_pixels
    host, dev = r.accumulators()
    ex = r.executor
    stats = r.start_stats()
    d_list = cl.Buffer(r.ctx, cl.mem_flags.READ_ONLY, max(4, 4 * n))
    # one launch per round with each pixel's own samples (the megakernel's render_spans); otherwise (the wavefront,
    # the feature AOVs' pass) a list launch per distinct span: the same sums either way
    spans_kernel = getattr(ex, "spans", False) and getattr(r, "_features", None) is None
    d_spans = cl.Buffer(r.ctx, cl.mem_flags.READ_ONLY, max(8, 8 * n)) if spans_kernel else None
    ex.warm_list(d_list)
    wait_for(r.queue)
    done = np.zeros(n, np.int64)               # each pixel's samples so far (its next sample's number)
    marks = opts.checkpoints()
    seconds_per_sample = None                  # per pixel-sample, measured over the launches so far
    bar = None
    if progress:
        from tqdm import tqdm

        # the most rounds there can be (one per checkpoint); a render usually takes a handful
        bar = tqdm(total=len(marks), unit="round", desc="adaptive", dynamic_ncols=True, leave=True)
    notice = None if bar is None else "\nclrender: Ctrl-C: stopping after the launch in flight (Ctrl-C again aborts)\n"
    t_start = last_partial = time.perf_counter()
    rounds = 0
    switch = {}                                # the switch to uniform sampling, once decided (metadata)
    conv = np.zeros((r.height, r.width), bool)

    def film_now(snapshot: bool = False):
        st = copy.copy(stats) if snapshot else stats
        st.seconds = time.perf_counter() - t_start
        f = r._film(int(done.max()), seed, 0, st, host, dev, 0, n, partial=snapshot)
        st.samples = int(done.sum())
        f.layers = ("count",)
        f.metadata.update(adaptive=True, target_error=opts.target_error, allocation=opts.allocation,
                          min_spp=opts.min_spp,
                          max_spp=opts.max_spp, spp_mean=round(float(done.mean()), 3), rounds=rounds,
                          converged=round(float(conv.mean()), 6), **switch)
        return f

    def must_stop(flag, dt: float) -> bool:
        """After a launch that took `dt` seconds: Ctrl-C, or a time limit the next such launch would pass."""
        if flag.requested:
            stats.interrupted = True
            return True
        return time_limit is not None and time.perf_counter() - t_start + dt > time_limit

    def run_uniform(target: int, flag) -> bool:
        """A splatting film's uniform rest (after the switch): every pixel on to `target` samples by passes of the
        uniform film (SplatExecutor.run_pass), each of about TARGET_LAUNCH_SECONDS; True when the render must
        stop."""
        nonlocal seconds_per_sample
        while done[0] < target:
            batch = min(target - int(done[0]), ex.max_spp(0, n))
            if seconds_per_sample is not None:
                batch = min(batch, max(1, int(TARGET_LAUNCH_SECONDS / max(seconds_per_sample * n, 1e-15))))
            t0 = time.perf_counter()
            stats.launches += ex.run_pass(0, n, int(done[0]), batch, seed & 0xFFFFFFFF)
            wait_for(r.queue)
            dt = time.perf_counter() - t0
            seconds_per_sample = dt / max(batch * n, 1)
            done[:] += batch
            if must_stop(flag, dt):
                return True
        return False

    def run_round(pixels, target, flag) -> bool:
        """Launches that take each of `pixels` from its samples so far to `target`; True when the render must
        stop (Ctrl-C, time limit) after the launch in flight."""
        nonlocal seconds_per_sample
        if switch and hasattr(ex, "settle"):
            return run_uniform(int(target[0]), flag)
        start = done[pixels]
        if len(pixels) == n and np.all(start == start[0]) and np.all(target == target[0]):
            segments = [(0, n)]                # all pixels, one span: range launches, no list to upload
            listed = False
        else:
            listed = True
            if spans_kernel:                   # the longest first: the launch's tail is its short spans
                order = np.argsort(start - target, kind="stable")
                segments = [(0, len(pixels))]
                spans = np.stack([start, target - start], axis=-1)[order].astype(np.uint32)
                cl.enqueue_copy(r.queue, d_spans, spans)
            else:                              # grouped by span, one list launch per group
                order = np.lexsort((target, start))
                key = (start * (opts.max_spp + 1) + target)[order]
                cuts = [0, *np.flatnonzero(np.diff(key)) + 1, len(pixels)]
                segments = list(zip(cuts, cuts[1:]))
            pixels, start, target = pixels[order], start[order], target[order]
            cl.enqueue_copy(r.queue, d_list, pixels.astype(np.uint32))
        steps = target - start
        for a, b in segments:
            off = a
            cum = np.cumsum(steps[a:b])
            while off < b:
                # Launches of about TARGET_LAUNCH_SECONDS; their size does not change any pixel's sums.
                cnt = r.launch_pixels
                if seconds_per_sample is not None:
                    before = cum[off - a - 1] if off > a else 0
                    fit = int(np.searchsorted(cum, before + TARGET_LAUNCH_SECONDS / max(seconds_per_sample, 1e-15),
                                              side="right")) - (off - a)
                    cnt = min(cnt, max(LOCAL_SIZE, fit // LOCAL_SIZE * LOCAL_SIZE))
                cnt = min(cnt, b - off)
                t0 = time.perf_counter()
                if not listed:
                    r.launch(off, cnt, int(start[off]), int(steps[off]), seed & 0xFFFFFFFF)
                elif spans_kernel:
                    ex.launch_spans(off, cnt, d_list, d_spans, seed & 0xFFFFFFFF)
                else:
                    r.launch(off, cnt, int(start[off]), int(steps[off]), seed & 0xFFFFFFFF, pixel_list=d_list)
                wait_for(r.queue)
                dt = time.perf_counter() - t0
                seconds_per_sample = dt / max(int(steps[off:off + cnt].sum()), 1)
                stats.launches += 1
                done[pixels[off:off + cnt]] = target[off:off + cnt]
                off += cnt
                if must_stop(flag, dt):
                    return True
        return False

    stop = False
    with _SigintFlag(notice) as flag:
        try:
            pixels = np.arange(n, dtype=np.int64)
            target = np.full(n, marks[0], np.int64)
            uniform_marks = []
            while len(pixels):
                if on_round is not None:
                    on_round(rounds, int(target.max()), len(pixels))
                if bar is not None:
                    bar.set_postfix_str(f"{len(pixels)} pixels to {int(target.min())}-{int(target.max())} spp")
                stop = run_round(pixels, target, flag)
                rounds += 1
                stats.passes += 1
                if bar is not None:
                    bar.update(1)
                if stop:
                    break
                if switch:                     # a uniform render: no tests
                    if not uniform_marks:
                        break
                    target = np.full(n, uniform_marks.pop(0), np.int64)
                    continue
                film = film_now()
                if rounds == 1 and len(marks) > 1 and marks[0] >= SWITCH_MIN_SPP:
                    gain, uniform_spp = predicted_allocation(film, opts)
                    if gain < opts.uniform_below:
                        # Even noise: adaptive allocation cannot win back the time its rounds cost. Every pixel
                        # on to the spp that gives uniform sampling the allocation's expected relMSE, in rounds
                        # over ranges (the checkpoints below it: progress, Ctrl-C and time limits as before).
                        switch = dict(uniform_after=marks[0], uniform_spp=max(marks[0], uniform_spp),
                                      predicted_gain=round(gain, 4))
                        uniform_marks = [m for m in marks[1:] if m < uniform_spp] + [uniform_spp] \
                            if uniform_spp > marks[0] else []
                        if progress:
                            print(f"clrender: adaptive: the noise is even (potential gain {gain:.2f} < "
                                  f"{opts.uniform_below:g}): a uniform render of {switch['uniform_spp']} spp",
                                  file=sys.stderr)
                        if bar is not None:
                            bar.total = rounds + len(uniform_marks)
                            bar.refresh()
                        if not uniform_marks:
                            break
                        if hasattr(ex, "settle"):   # a splatting film: on as a uniform render (run_uniform)
                            ex.settle()
                        target = np.full(n, uniform_marks.pop(0), np.int64)
                        continue
                # the test, of the pixels this round added to (the others met the target in earlier rounds)
                # (few pixels: the errors of their neighbourhoods only)
                terms, nb = _pooled_terms(film, pixels)
                met = _pooled(terms) <= _bound(done[pixels], opts)
                conv.reshape(-1)[pixels] = met
                going_on = ~met & (done[pixels] < opts.max_spp)
                goes = np.zeros(n, bool)
                goes[pixels[going_on]] = True
                terms, goes = terms[going_on], goes[nb[going_on]]
                pixels = pixels[going_on]
                # Each pixel on to the count its error predicts, in one launch (the fewer rounds, the less of
                # their fixed cost and of small launches' idle cores); tested there as before.
                target = next_counts(done[pixels], (terms * goes).sum(axis=1) / 9.0,
                                     (terms * ~goes).sum(axis=1) / 9.0, opts, marks)
                if partial is not None and len(pixels) and time.perf_counter() - last_partial >= partial[0]:
                    partial[1](film_now(snapshot=True))
                    last_partial = time.perf_counter()
        finally:
            if bar is not None:
                bar.close()
    film = film_now()
    if not stop:
        conv = converged(film, opts.target_error, opts.allocation, opts.min_spp)
        film.metadata["converged"] = round(float(conv.mean()), 6)
    return film


# -- command line ------------------------------------------------------------------------------------------------
def add_render_arguments(r) -> None:
    g = r.add_argument_group("adaptive sampling")
    g.add_argument("--adaptive", action="store_true",
                   help="render in rounds over the pixels whose relative error is above --target-error (default "
                        "0.01) until all meet it or --max-spp")
    g.add_argument("--target-error", type=float, metavar="E",
                   help="relative standard error each pixel should reach (e.g. 0.01; values below 0.1 count as "
                        "0.1); implies --adaptive")
    g.add_argument("--min-spp", type=int, metavar="N", help="samples every pixel gets before its first test "
                                                            "(default 16)")
    g.add_argument("--max-spp", type=int, metavar="N",
                   help="samples per pixel at most (default: --spp, else the scene's sample count)")
    g.add_argument("--allocation", choices=ALLOCATIONS, default="error",
                   help="error (default): every pixel to the target error; relmse: the least relMSE of the whole "
                        "image for its samples (a pixel's bound grows as sqrt(its samples / min-spp): noisy pixels "
                        "get more samples, not all they would need)")
    g.add_argument("--always-adaptive", action="store_true",
                   help="never finish as a uniform render (by default, when after the first round the noise is "
                        f"even, potential gain below {UNIFORM_BELOW}, every pixel goes on to one sample count)")


def options_from_args(args, scene) -> AdaptiveOptions | None:
    """The adaptive options of `clrender render`'s arguments (None: a uniform render); ClrenderError if they are
    wrong or are combined with what they do not work with."""
    from .errors import ClrenderError

    wanted = args.adaptive or args.target_error is not None
    if not wanted:
        if args.min_spp is not None or args.max_spp is not None or args.allocation != "error" or \
                args.always_adaptive:
            raise ClrenderError("--min-spp, --max-spp, --allocation and --always-adaptive are options of adaptive "
                                "sampling: add --adaptive or --target-error E")
        return None
    if scene is None:   # before the distributed renders
        if getattr(args, "cluster", None) or getattr(args, "sample_range", None):
            raise ClrenderError("adaptive sampling runs in one process: it cannot be combined with --cluster or "
                                "--sample-range (each round depends on the samples of all before it)")
        return None
    if args.spp is not None and args.max_spp is not None:
        raise ClrenderError("--spp and --max-spp both set the most samples per pixel of an adaptive render: give one")
    try:
        return AdaptiveOptions.make(0.01 if args.target_error is None else args.target_error, args.min_spp,
                                    args.max_spp if args.max_spp is not None else args.spp, scene.sample_count,
                                    args.allocation, 0.0 if args.always_adaptive else UNIFORM_BELOW)
    except ValueError as e:
        raise ClrenderError(f"adaptive sampling: {e}") from None
