"""The pass loop: upload the packed scene, launch render passes, watch time and Ctrl-C, build the Film.

A pass adds `spp` samples to every pixel (the image is cut into fixed-size launches so each launch stays
short). Samples are numbered globally, so the image is the same however the work is split into passes.
Ctrl-C sets a flag that is checked between passes: the pass in flight finishes, the partial image keeps
its true sample count; a second Ctrl-C aborts at once (the host polls the queue instead of blocking in
clFinish, so Python's signal handler runs while the device works).
"""
from __future__ import annotations

import copy
import time
from dataclasses import dataclass

import numpy as np

from .version import __version__
from .device import layout
from .device.context import get_context
from .device.program import build_program
from .executors import (LOCAL_SIZE, TARGET_LAUNCH_SECONDS, DriverError, MegakernelExecutor, SplatExecutor,
                        WavefrontExecutor, choose_driver, choose_reconstruction)
from .film import Film
from .interrupt import Interrupted, PassFlag as _SigintFlag, wait_for  # noqa: F401  (Interrupted: the API)
from .memcheck import check_film_fits
from .pack import pack_scene

MAX_LAUNCH_PIXELS = 1 << 16  # pixels per launch; a pass over a larger image is several launches


def render_defines(scene, buffers, extra: dict | None = None) -> dict:
    """The -D defines of a program over `buffers`: the scene's integrator (if a scene is given), the BVH layout
    the packer chose (always passed, so kernels/scene.h's own default never has to agree with the host's) and the
    device plugins the tables use (the program compiles only those; ``extra={"CLR_USE_ALL_PLUGINS": 1}`` builds
    the full program, which gives the same image)."""
    defines = {} if scene is None else {"INTEGRATOR": scene.integrator.kernel}
    defines["BVH_WIDTH"] = buffers.bvh_width
    if getattr(buffers, "sampler", "independent") == "sobol":
        defines["CLR_SAMPLER_SOBOL"] = 1
    if getattr(buffers, "plugins", None) is not None:
        defines.update(buffers.plugins.defines())
    if isinstance(getattr(buffers, "tables", None), dict) and "info" in buffers.tables:
        # fixed trip counts for the searches and the loops over infinite emitters (kernels/math.h, emitter.h):
        # no per-item loop is left in a stage kernel for them
        defines["CLR_SEARCH_STEPS"] = buffers.search_steps
        defines["CLR_N_INFINITE"] = int(buffers.tables["info"]["n_infinite"][0])
        if int(buffers.tables["info"]["n_media"][0]):   # volpath's media code (kernels/integrators/media.h)
            defines["CLR_MEDIA"] = 1
    return {**defines, **(extra or {})}


def samples_border(scene) -> bool:
    """Whether the scene's film places samples outside its window (Mitsuba's sample_border); a cluster worker's
    shipped scene says so itself (cluster_worker.ShippedScene)."""
    if hasattr(scene, "sample_border"):
        return bool(scene.sample_border)
    return bool(getattr(getattr(getattr(scene, "camera", None), "film", None), "sample_border", False))


def splat_reach(camera_row) -> int:
    """How many pixels away a splatted sample counts (kernels/splat.cl splat_reach, in the same float32)."""
    return max(0, int(np.ceil(np.float32(camera_row["filter_radius"][0]) - np.float32(0.5))))


@dataclass
class RenderStats:
    seconds: float = 0.0
    samples: int = 0
    passes: int = 0
    launches: int = 0
    build_seconds: float = 0.0
    upload_seconds: float = 0.0
    interrupted: bool = False
    dropped: int = 0
    #: rays traced, (camera, closest-hit other than camera, shadow); None unless the Renderer counts rays
    rays: tuple | None = None

    @property
    def rays_total(self) -> int | None:
        return None if self.rays is None else int(sum(self.rays))


class Renderer:
    """A scene uploaded to one device, with its program built; `render()` may be called repeatedly.

    With ``count_rays=True`` the kernels are built with ``-DCLRENDER_COUNT_RAYS`` and every render reports the
    rays it traced (``film.stats.rays``, ``film.metadata["rays_*"]``); normal builds compile no counting code.
    ``driver`` picks how passes run (clrender/executors.py): "megakernel", "wavefront" (path integrators only) or
    "auto" (the faster one; ``self.driver`` says which).
    ``reconstruction``: how the film turns samples into pixels (executors.choose_reconstruction): "splat" is
    Mitsuba's and Nori's film (kernels/splat.cl: each sample, placed uniformly in its pixel, counts in every pixel
    within the filter's radius), "sampling" filter importance sampling (render.cl: each sample in one pixel),
    "auto" splats wherever it can (``self.splat`` says which). The same expected image; a splatting film has
    about a third of the noise variance per pixel with Mitsuba's default Gaussian filter, and neighbouring pixels'
    noise is correlated. Adaptive sampling splats too, each pixel's samples weighed by 1 / its count
    (SplatExecutor's store), unless the store does not fit the device or the film has ``sample_border`` (the store
    holds the window's pixels only): then it samples the filter.
    """

    def __init__(self, scene, device=None, fast_math: bool = False, buffers=None, defines=None,
                 count_rays: bool = False, driver: str = "auto", feature_aovs: bool = False,
                 reconstruction: str = "auto"):
        import pyopencl as cl

        self.scene = scene
        self.count_rays = bool(count_rays)
        self.feature_aovs = bool(feature_aovs)
        defines = dict(defines or {})
        if self.count_rays:
            defines["CLRENDER_COUNT_RAYS"] = 1
        if self.feature_aovs:   # only then: a program without them is the very program it always was
            defines["CLR_FEATURE_AOVS"] = 1
        self.ctx, self.queue = get_context(device)
        dev = self.ctx.devices[0]
        self.device_name = f"{dev.platform.name.strip()} / {dev.name.strip()}"
        check_film_fits(scene, dev, self.count_rays, splat=reconstruction != "sampling")
        self.buffers = buffers if buffers is not None else pack_scene(scene)
        t0 = time.perf_counter()
        #: the -D defines of the render program (`clrender bench` times builds of this very program)
        self.defines = render_defines(scene, self.buffers, defines)
        self.driver = choose_driver(driver, scene.integrator.kernel, self.count_rays)
        if self.driver == "wavefront" and "CLR_MEDIA" in self.defines:
            raise DriverError("the wavefront driver does not render participating media (the scene has "
                              f"{int(self.buffers.tables['info']['n_media'][0])}): use --driver megakernel")
        self._init_args = dict(device=device, fast_math=fast_math, defines=defines, driver=driver,
                                feature_aovs=feature_aovs)
        self.reconstruction = reconstruction
        self.splat = choose_reconstruction(reconstruction, self.driver, self.count_rays,
                                           splat_reach(self.buffers.camera), self.feature_aovs)
        #: pixels around the window whose samples a splatting film draws too (Mitsuba's sample_border)
        self.splat_border = splat_reach(self.buffers.camera) if self.splat and samples_border(scene) else 0
        self._sampling = None
        if self.splat:
            self.defines["CLR_SPLAT"] = 1
            self.defines["CLR_SPLAT_K"] = 2 * splat_reach(self.buffers.camera) + 1   # adaptive sampling's store
            self.defines["CLR_SPLAT_BORDER"] = self.splat_border
        main = '#include "splat.cl"\n' if self.splat else \
            {"wavefront": '#include "wavefront.cl"\n', "megakernel": '#include "render.cl"\n'}[self.driver]
        self.program = build_program(self.ctx, main, defines=self.defines, fast_math=fast_math)
        self.build_seconds = time.perf_counter() - t0
        t0 = time.perf_counter()
        mf = cl.mem_flags
        ro = mf.READ_ONLY | mf.COPY_HOST_PTR
        b = self.buffers
        self._scene_bufs = {n: cl.Buffer(self.ctx, ro, hostbuf=np.ascontiguousarray(a)) for n, a in b.tables.items()}
        self._camera = cl.Buffer(self.ctx, ro, hostbuf=b.camera)
        self._filter = cl.Buffer(self.ctx, ro, hostbuf=b.filter_cdf)
        self.width, self.height = scene.width, scene.height
        self.n_pixels = self.width * self.height
        self.launch_pixels = min(self.n_pixels, MAX_LAUNCH_PIXELS)
        if self.splat:
            self.executor = SplatExecutor(self.ctx, self.queue, self.program, self._scene_bufs, self._camera,
                                          self.width, self.height, splat_reach(b.camera), self.launch_pixels,
                                          self.splat_border)
        else:
            executor = WavefrontExecutor if self.driver == "wavefront" else MegakernelExecutor
            self.executor = executor(self.ctx, self.queue, self.program, self._scene_bufs, self._camera,
                                     self._filter, self.launch_pixels)
        self.global_size = -(-self.launch_pixels // LOCAL_SIZE) * LOCAL_SIZE   # the megakernel's launch shape
        self._features = None
        if self.feature_aovs:
            from .device.kernelargs import KernelArgs

            self._features = KernelArgs(cl.Kernel(self.program, "feature_pass")).set_scene(self._scene_bufs)
            self._features.set(cam=self._camera, filter_cdf=self._filter)
            self._no_list = cl.Buffer(self.ctx, mf.READ_ONLY, 4)
        if self.driver == "megakernel" and not self.splat:   # the benchmarks launch render_pass themselves
            self.kernel, self.args = self.executor.kernel, self.executor.args
        self.upload_seconds = time.perf_counter() - t0
        self._warm = False

    def device_memory_bytes(self) -> int:
        """Bytes this renderer keeps on the device during a render: scene tables, camera, filter table,
        and the per-pixel accumulators (layout.film_buffers: the ray counters' one-element dummy when not
        counting)."""
        fixed = sum(a.nbytes for a in self.buffers.scene_arrays())
        fixed += self.buffers.camera.nbytes + self.buffers.filter_cdf.nbytes
        fixed += getattr(self.executor, "device_bytes", 0)   # the wavefront's path state, the splat records
        return int(fixed + layout.film_bytes(self.n_pixels, self.count_rays, self.splat))

    def accumulators(self):
        """Zeroed per-pixel accumulators on the host and the device ({name: array}, {name: buffer} of
        layout.FILM_ACCUMULATORS), bound to the executor; the feature AOVs' too, when asked for."""
        import pyopencl as cl

        n = self.n_pixels
        host, dev = {}, {}
        mf = cl.mem_flags
        for name, full in layout.film_buffers(self.count_rays, self.splat):
            dt, shape = layout.film_element(name)
            host[name] = np.zeros((n if full else 1, *shape), dt)
            dev[name] = cl.Buffer(self.ctx, mf.READ_WRITE | mf.COPY_HOST_PTR, hostbuf=host[name])
        self.executor.bind(dev)
        if self._features is not None:   # kernels/feature_aovs.h: three float4 per pixel
            feat = np.zeros((n, 12), np.float32)
            self._feature_acc = (feat, cl.Buffer(self.ctx, mf.READ_WRITE | mf.COPY_HOST_PTR, hostbuf=feat))
            self._features.set(aov=self._feature_acc[1])
        return host, dev

    def launch(self, off: int, count: int, sample_offset: int, spp: int, seed: int, pixel_list=None) -> None:
        """The executor's launch (clrender/executors.py), and the feature AOVs' of the same samples if asked for (a
        splatting film's launches go to its store, for pixels with counts of their own: adaptive sampling)."""
        self.executor.launch(off, count, sample_offset, spp, seed, pixel_list=pixel_list)
        self._launch_features(off, count, sample_offset, spp, seed, pixel_list)

    def _launch_features(self, off, count, sample_offset, spp, seed, pixel_list=None) -> None:
        if self._features is not None:
            import pyopencl as cl

            self._features.set(pixel_list=self._no_list if pixel_list is None else pixel_list,
                               listed=np.uint32(pixel_list is not None), pixel_offset=np.uint32(off),
                               pixel_count=np.uint32(count), sample_offset=np.uint32(sample_offset),
                               spp=np.uint32(spp), seed=np.uint32(seed))
            cl.enqueue_nd_range_kernel(self.queue, self._features.kernel, (self.global_size,), (LOCAL_SIZE,))

    def start_stats(self) -> RenderStats:
        """The stats of a render about to start; warms the executor first if it is cold: PoCL compiles the
        work-group function at the first launch of a shape (0.3-2 s), done with a launch that adds no samples, so
        timings, pass sizes and the ETA are those of the render."""
        if not self._warm:
            t0 = time.perf_counter()
            self.executor.warm()
            self._launch_features(0, 0, 0, 0, 0)
            wait_for(self.queue)
            self._warm = True
            self.build_seconds += time.perf_counter() - t0
        return RenderStats(build_seconds=self.build_seconds, upload_seconds=self.upload_seconds)

    def render_adaptive(self, target_error: float = 0.01, min_spp: int | None = None, max_spp: int | None = None,
                        seed: int = 0, time_limit: float | None = None, progress: bool = False,
                        partial=None, on_round=None, allocation: str = "error",
                        uniform_below: float | None = None) -> Film:
        """Adaptive sampling: rounds over the pixels whose estimate's relative error is still above
        `target_error` (clrender/adaptive.py); `max_spp` defaults to the scene's sample count; where the noise is
        even it finishes as a uniform render (`uniform_below`: the potential gain below which; 0: never)."""
        from .adaptive import UNIFORM_BELOW, AdaptiveOptions, render_adaptive

        if self.splat and (self.splat_border or not self.store_fits()):
            if self.splat_border and self.reconstruction != "auto":
                raise DriverError("adaptive sampling's splatting film holds the window's pixels only, not the "
                                  "samples sample_border places around it: use --reconstruction sampling or auto")
            if self.reconstruction != "auto":
                gib = sum(self.executor.store_buffer_bytes()) / 2**30
                raise DriverError(f"adaptive sampling's splatting film needs {gib:.1f} GiB of device memory for this "
                                  "image, more than the device gives it: use --reconstruction sampling or auto")
            if self._sampling is None:   # the same scene tables, the filter-sampling program
                self._sampling = Renderer(self.scene, buffers=self.buffers, reconstruction="sampling",
                                          **self._init_args)
            return self._sampling.render_adaptive(target_error, min_spp, max_spp, seed, time_limit, progress,
                                                  partial, on_round, allocation, uniform_below)
        opts = AdaptiveOptions.make(target_error, min_spp, max_spp, self.scene.sample_count, allocation,
                                    UNIFORM_BELOW if uniform_below is None else uniform_below)
        return render_adaptive(self, opts, seed=seed, time_limit=time_limit, progress=progress, partial=partial,
                               on_round=on_round)

    def store_fits(self) -> bool:
        """Whether a splatting film's store for adaptive sampling (SplatExecutor.store_buffer_bytes) fits the device:
        its largest buffer within one allocation, all of it within half the device's memory."""
        dev = self.ctx.devices[0]
        sizes = self.executor.store_buffer_bytes()
        return (max(sizes) <= dev.max_mem_alloc_size
                and sum(sizes) + self.device_memory_bytes() <= dev.global_mem_size // 2)

    def render(self, spp: int | None = None, seed: int = 0, time_limit: float | None = None,
               progress: bool = False, on_pass=None, start_sample: int = 0, pixels=None,
               partial=None) -> Film:
        """Render `spp` samples per pixel (default: the scene's sampler), numbered from `start_sample`.

        ``pixels=(first, stop)`` renders only that range of pixel indices (row-major; a band of rows for a
        cluster task): the Film is full-size with zeros elsewhere. ``partial=(seconds, callback)`` hands
        ``callback`` the Film so far (its metadata: the samples done, ``partial`` True) after the first pass that
        ends at least `seconds` after the previous one (or the start), between passes."""
        return self._render(self._film, spp, seed, time_limit, progress, on_pass, start_sample, pixels, partial)

    def render_accumulators(self, spp: int, seed: int = 0, start_sample: int = 0, pixels=None) -> dict:
        """Render as `render` does and return the device's accumulators of the pixels rendered as it summed them
        (float32 and uint32, by their names in layout.FILM_ACCUMULATORS, without the ray counters): what a
        cluster task sends back, without a Film's float64 copy of the whole film."""
        def band(done, seed, start_sample, stats, host, dev, p0, p1):
            self._download(host, dev, p0, p1)
            # copies: the band alone travels and stays, not the whole film's arrays behind it
            return {name: host[name][p0:p1].copy() for name in self.accumulator_names()}

        return self._render(band, spp, seed, None, False, None, start_sample, pixels, None)

    def _render(self, finish, spp, seed, time_limit, progress, on_pass, start_sample, pixels, partial):
        spp = int(spp if spp is not None else self.scene.sample_count)
        if spp < 1:
            raise ValueError("spp must be at least 1")
        if start_sample < 0 or start_sample + spp >= 2**32:
            raise ValueError("sample numbers (start_sample + spp) must stay below 2^32")
        if time_limit is not None and not (time_limit > 0 and np.isfinite(time_limit)):
            raise ValueError(f"time_limit must be a positive finite number of seconds, got {time_limit}")
        n = self.n_pixels
        p0, p1 = (0, n) if pixels is None else (int(pixels[0]), int(pixels[1]))
        if not 0 <= p0 < p1 <= n:
            raise ValueError(f"pixel range {p0}:{p1} is not inside 0:{n}")
        host, dev = self.accumulators()
        stats = self.start_stats()
        done = 0
        per_pass = 1
        bar = None
        if progress:  # after the warm-up launch: the bar says rendering has started (a Ctrl-C now keeps an image)
            from tqdm import tqdm

            bar = tqdm(total=spp, unit="spp", desc="rendering", dynamic_ncols=True, leave=True)
        t_start = time.perf_counter()
        last_partial = t_start
        notice = None if bar is None else \
            "\nclrender: Ctrl-C: stopping after the pass in flight (Ctrl-C again aborts)\n"
        with _SigintFlag(notice) as flag:
            try:
                while done < spp:
                    batch = min(per_pass, spp - done)
                    t0 = time.perf_counter()
                    if self.splat:
                        batch = min(batch, self.executor.max_spp(p0, p1))
                        stats.launches += self.executor.run_pass(p0, p1, start_sample + done, batch,
                                                                 seed & 0xFFFFFFFF)
                        for off in range(p0, p1, self.launch_pixels):
                            self._launch_features(off, min(self.launch_pixels, p1 - off), start_sample + done,
                                                  batch, seed & 0xFFFFFFFF)
                    else:
                        for off in range(p0, p1, self.launch_pixels):
                            cnt = min(self.launch_pixels, p1 - off)
                            self.launch(off, cnt, start_sample + done, batch, seed & 0xFFFFFFFF)
                            stats.launches += 1
                    wait_for(self.queue)  # not queue.finish(): a second Ctrl-C must not wait for the pass
                    dt = time.perf_counter() - t0
                    done += batch
                    stats.passes += 1
                    # Decided before the bar shows the pass: a Ctrl-C pressed after seeing it lets the next
                    # pass run (it is the pass in flight for whoever pressed), whatever the timing.
                    stop = flag.requested
                    if bar is not None:
                        bar.update(batch)
                    if on_pass is not None:
                        on_pass(done)
                    if partial is not None and not stop and done < spp and \
                            time.perf_counter() - last_partial >= partial[0]:
                        snap = copy.copy(stats)   # the render's own stats go on counting
                        snap.seconds = time.perf_counter() - t_start
                        partial[1](self._film(done, seed, start_sample, snap, host, dev, p0, p1, partial=True))
                        last_partial = time.perf_counter()
                    if stop:
                        stats.interrupted = True
                        break
                    launches = -(-(p1 - p0) // self.launch_pixels)
                    per_launch = dt / max(launches, 1) / batch  # seconds per sample per launch
                    per_pass = max(1, int(TARGET_LAUNCH_SECONDS / max(per_launch, 1e-9)))
                    if time_limit is not None:
                        elapsed = time.perf_counter() - t_start
                        remaining = time_limit - elapsed
                        per_sample = dt / batch
                        if remaining < per_sample:
                            break
                        per_pass = max(1, min(per_pass, int(remaining / per_sample)))
            finally:
                if bar is not None:
                    bar.close()
        stats.seconds = time.perf_counter() - t_start
        return finish(done, seed, start_sample, stats, host, dev, p0, p1)

    def accumulator_names(self) -> list[str]:
        """The per-pixel sums a render of this renderer sends back (what a cluster task returns, without the ray
        counters): layout.film_buffers'."""
        return [name for name, full in layout.film_buffers(False, self.splat) if full]

    def _download(self, host, dev, p0, p1) -> None:
        """Copy pixels p0:p1 of the device's accumulators into `host` (only the rendered range: a band of a 4K film
        need not download the whole film)."""
        import pyopencl as cl

        for name, a in host.items():
            if len(a) == self.n_pixels:   # (not a one-element dummy)
                cl.enqueue_copy(self.queue, a[p0:p1], dev[name], src_offset=p0 * a[0].nbytes)
        if self._features is not None:
            feat, d_feat = self._feature_acc
            cl.enqueue_copy(self.queue, feat[p0:p1], d_feat, src_offset=p0 * feat[0].nbytes)
        self.queue.finish()

    def _film(self, done, seed, start_sample, stats, host, dev, p0, p1, partial=False) -> Film:
        """The Film of the `done` samples per pixel accumulated on the device so far (pixels p0:p1); fills in
        `stats`."""
        if self.splat:
            self.executor.resolve()   # adaptive sampling's store, if it was used, into the film's sums
        self._download(host, dev, p0, p1)
        stats.samples = done * (p1 - p0)
        stats.dropped = int(host["bad"].sum())
        meta = {
            "spp": done, "seed": seed, "render_seconds": round(stats.seconds, 4), "device": self.device_name,
            "integrator": self.scene.integrator.kernel, "version": __version__,
            "interrupted": stats.interrupted, "dropped_samples": stats.dropped, "start_sample": start_sample,
            "nori_dialect": getattr(self.scene, "nori_dialect", "upstream"),
        }
        if self.splat:
            meta["film"] = "splat"
            rfilter = getattr(getattr(self.scene, "camera", None), "filter", None)
            if rfilter is not None:
                meta["splat_pool"] = round(rfilter.splat_pool_factor(), 4)
        if partial:
            meta["partial"] = True
        if self.count_rays:
            tot = host["rays"][:, :3].astype(np.uint64).sum(axis=0)
            stats.rays = (int(tot[0]), int(tot[1]), int(tot[2]))
            meta.update(rays_camera=stats.rays[0], rays_closest=stats.rays[1], rays_shadow=stats.rays[2],
                        rays_total=stats.rays_total)
        film = Film.from_accumulators(self.width, self.height, host, meta)
        if self._features is not None:
            film.features = self._feature_acc[0].astype(np.float64).reshape(self.height, self.width, 12)
        stats.dropped = int(film.dropped.sum())  # with the samples of pixels whose sums overflowed
        film.stats = stats
        film.tonemap = getattr(getattr(self.scene.camera, "film", None), "tonemap", None)  # an ldrfilm's 8-bit image
        film.moment = getattr(self.scene, "moment_channels", None)   # a `moment` integrator's m2 channels
        return film


def aov_channels(scene, spp: int | None = None, seed: int = 0, device=None, driver: str = "auto") -> dict:
    """The channels of the AOVs a Mitsuba `aov` with a nested integrator asks for (``scene.aovs``), each rendered by
    a pass of the aov integrator alone with the same samples per pixel and seed, named as Mitsuba 3.9.1 names them:
    ``<name>.T`` for depth (one channel), ``<name>.X/.Y/.Z`` for the others. {} where there are none."""
    from .scene.registry import instantiate

    out = {}
    for name, kind in getattr(scene, "aovs", ()):
        view = copy.copy(scene)
        view.integrator = instantiate("integrator", "aov", {"aovs": ("string", f"{name}:{kind}")}, fmt="mitsuba")
        img = Renderer(view, device=device, driver=driver).render(spp=spp, seed=seed).image
        if kind == "depth":
            out[f"{name}.T"] = img[..., 0]
        else:
            out.update({f"{name}.{c}": img[..., i] for i, c in enumerate("XYZ")})
    return out


def render(scene, spp: int | None = None, seed: int = 0, device=None, time_limit: float | None = None,
           progress: bool = False, driver: str = "auto", reconstruction: str = "auto") -> Film:
    """Render a loaded scene; returns the Film (``film.image`` is the (H, W, 3) float32 image)."""
    return Renderer(scene, device=device, driver=driver, reconstruction=reconstruction).render(
        spp=spp, seed=seed, time_limit=time_limit, progress=progress)
