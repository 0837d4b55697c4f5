"""Adaptive sampling to a target error: render in rounds, each over only the pixels whose estimate is not yet good
enough, until every pixel meets the target, at `max_spp`, at the time limit or at Ctrl-C.

The rounds end at fixed sample counts (`checkpoints`: `min_spp`, then a quarter more each round, up to `max_spp`),
the same for every pixel and every run. A pixel's samples are numbered 0, 1, 2, ... as in a uniform render (its
n samples are those a uniform render of n spp gives it), and a round adds the samples of one checkpoint interval to
each listed pixel in one kernel call (kernels/render.cl render_list, wavefront.cl's listed launches): its sums
depend only on its own samples and the checkpoints, never on how the list is cut into launches, on the executor's
wave size or on timing. So whether a pixel goes on after a round is a function of its own (and its neighbours')
samples, and the same seed and options give the same image and the same per-pixel counts however the work is
split (tests/test_adaptive.py). A time limit or Ctrl-C stops between launches; the image keeps its true
per-pixel counts (``film.count``, the EXR's ``count`` layer).

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
"""
from __future__ import annotations

import copy
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


#: how the samples are shared out: "error", every pixel to the target error; "relmse", the least relMSE of the image
ALLOCATIONS = ("error", "relmse")


@dataclass(frozen=True)
class AdaptiveOptions:
    target_error: float
    min_spp: int
    max_spp: int
    allocation: str = "error"

    @classmethod
    def make(cls, target_error, min_spp=None, max_spp=None, default_max_spp: int = 64,
             allocation: str = "error") -> "AdaptiveOptions":
        """Checked options; `max_spp` defaults to `default_max_spp` (the scene's sample count), `min_spp` to 16
        (at most max_spp). Raises ValueError naming the option that is wrong."""
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
        return cls(e, lo, hi, allocation)

    def checkpoints(self) -> list[int]:
        """The sample counts at which every still-active pixel is tested."""
        out = [self.min_spp]
        while out[-1] < self.max_spp:
            out.append(min(self.max_spp, out[-1] + max(self.min_spp, int(out[-1] * ROUND_GROWTH))))
        return out


def relative_error(film) -> np.ndarray:
    """(H, W) the pixel's error as the stopping rule sees it: the largest over channels of the standard error (from
    the variance's upper 95 % confidence limit) over max(|value|, 0.1) in quadrature, i.e.
    sqrt(var_up / (value^2 + 1e-2)). Pixels without two samples: inf."""
    from scipy.stats import chi2

    # the counts take a few values (the checkpoints): the quantile once per value (chi2.ppf per pixel took 11 % of
    # an adaptive render of a 128 x 128 Cornell box)
    counts, inverse = np.unique(film.count, return_inverse=True)
    dof = np.maximum(counts - 1, 1)
    factor = np.where(counts >= 2, dof / chi2.ppf(1.0 - CONFIDENCE, dof), np.inf)[inverse].reshape(film.count.shape)
    img = film.image.astype(np.float64)
    with np.errstate(invalid="ignore"):
        err2 = film.variance() * factor[..., None] / (img * img + RELMSE_EPS)
    err2 = np.where(np.isnan(err2), np.inf, err2)
    return np.sqrt(err2.max(axis=-1))


def pooled_error(film) -> np.ndarray:
    """(H, W) what the stopping rule tests: relative_error's square averaged over the pixel and its 8 neighbours (the
    image's edge repeats its border pixels), square-rooted."""
    err2 = np.minimum(relative_error(film) ** 2, 1e12)   # inf (fewer than two samples) as a huge error
    # nine shifted sums, not scipy's uniform_filter: its running sums lose small errors beside huge ones
    p = np.pad(err2, 1, mode="edge")
    h, w = err2.shape
    return np.sqrt(sum(p[i:i + h, j:j + w] for i in range(3) for j in range(3)) / 9.0)


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


def render_adaptive(renderer, opts: AdaptiveOptions, seed: int = 0, time_limit: float | None = None,
                    progress: bool = False, partial=None, on_round=None):
    """The adaptive render of `renderer`'s scene (see the module's docstring); returns its Film, whose ``count``
    holds each pixel's samples and whose metadata adds ``adaptive``, ``target_error``, ``min_spp``, ``max_spp``,
    ``spp_mean``, ``converged`` (the fraction of pixels that met the target) and ``rounds``. ``partial`` as
    Renderer.render's; ``on_round(round, checkpoint, n_active)`` is called before each round."""
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
    ex.warm_list(d_list)
    wait_for(r.queue)
    done = np.zeros(n, np.int64)               # each pixel's samples so far (its next sample's number)
    active = np.arange(n, dtype=np.uint32)
    marks = opts.checkpoints()
    seconds_per_sample = None                  # per pixel-sample, measured over the launches so far
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(marks), unit="round", desc="adaptive", dynamic_ncols=True, leave=True)
    notice = None if bar is None else "\nclrender: Ctrl-C: stopping after the launch in flight (Ctrl-C again aborts)\n"
    t_start = last_partial = time.perf_counter()
    rounds = 0

    def film_now(snapshot: bool = False):
        st = copy.copy(stats) if snapshot else stats
        st.seconds = time.perf_counter() - t_start
        f = r._film(int(done.max()), seed, 0, st, host, dev, 0, n, partial=snapshot)
        st.samples = int(done.sum())
        f.layers = ("count",)
        f.metadata.update(adaptive=True, target_error=opts.target_error, allocation=opts.allocation,
                          min_spp=opts.min_spp,
                          max_spp=opts.max_spp, spp_mean=round(float(done.mean()), 3), rounds=rounds,
                          converged=round(float(conv.mean()), 6))
        return f

    conv = np.zeros((r.height, r.width), bool)
    stop = False
    with _SigintFlag(notice) as flag:
        try:
            prev = 0
            for mark in marks:
                if on_round is not None:
                    on_round(rounds, mark, len(active))
                if bar is not None:
                    bar.set_postfix_str(f"{len(active)} pixels to {mark} spp")
                cl.enqueue_copy(r.queue, d_list, active)
                step = mark - prev
                off = 0
                while off < len(active):
                    # Launches of about TARGET_LAUNCH_SECONDS; their size does not change any pixel's sums.
                    cnt = r.launch_pixels
                    if seconds_per_sample is not None:
                        fit = int(TARGET_LAUNCH_SECONDS / max(seconds_per_sample * step, 1e-12))
                        cnt = min(cnt, max(LOCAL_SIZE, fit // LOCAL_SIZE * LOCAL_SIZE))
                    cnt = min(cnt, len(active) - off)
                    t0 = time.perf_counter()
                    r.launch(off, cnt, prev, step, seed & 0xFFFFFFFF, pixel_list=d_list)
                    wait_for(r.queue)
                    dt = time.perf_counter() - t0
                    seconds_per_sample = dt / (cnt * step)
                    stats.launches += 1
                    done[active[off:off + cnt]] = mark
                    off += cnt
                    if flag.requested:
                        stats.interrupted = stop = True
                    elif time_limit is not None and time.perf_counter() - t_start + dt > time_limit:
                        stop = True
                    if stop:
                        break
                rounds += 1
                stats.passes += 1
                if bar is not None:
                    bar.update(1)
                if stop:
                    break
                prev = mark
                film = film_now()
                conv = converged(film, opts.target_error, opts.allocation, opts.min_spp)
                keep = ~conv.reshape(-1)[active]
                active = active[keep]
                if len(active) == 0:
                    break
                if partial is not None and mark < opts.max_spp and \
                        time.perf_counter() - last_partial >= partial[0]:
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


def options_from_args(args, scene) -> AdaptiveOptions | None:
    """The adaptive options of `clrender render`'s arguments (None: a uniform render); ClrenderError if they are
    wrong or are combined with what they do not work with."""
    from .errors import ClrenderError

    wanted = args.adaptive or args.target_error is not None
    if not wanted:
        if args.min_spp is not None or args.max_spp is not None or args.allocation != "error":
            raise ClrenderError("--min-spp, --max-spp and --allocation are options of adaptive sampling: add "
                                "--adaptive or --target-error E")
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
                                    args.allocation)
    except ValueError as e:
        raise ClrenderError(f"adaptive sampling: {e}") from None
