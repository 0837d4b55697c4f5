"""The two ways of running a pass on the device, behind one interface (`Renderer` holds one of them).

- ``MegakernelExecutor``: render.cl's ``render_pass``, one work-item per pixel running the whole integrator.
- ``WavefrontExecutor``: wavefront.cl's stage kernels over queues of paths (the path integrators only): camera,
  trace, shade, shadow, finish, flush. A wave holds `k` consecutive samples of each pixel of a launch; its path
  state lives in device buffers sized by the kernels themselves (``wf_sizes``).

Both draw the same random numbers and sum each pixel's samples in the same order, so they give the same image up
to float rounding (tests/test_wavefront.py). ``launch`` enqueues a pass over pixels [off, off + count) of `spp`
samples numbered from `sample_offset`; the megakernel's returns at once, the wavefront's reads its queue sizes
between stages (small blocking reads), so it returns when its work is done.
"""
from __future__ import annotations

import numpy as np

from .device import layout
from .device.program import MIN_GENERIC_GLOBAL
from .errors import ClrenderError


class DriverError(ClrenderError, ValueError):
    """A driver that cannot run this render (reported like any bad option: no traceback, exit status 2)."""

#: integrators whose kernels are path.h's stages (kernels/integrators/path_loop.h): the wavefront can run them
WAVEFRONT_INTEGRATORS = frozenset({"path_mats", "path_ems", "path_mis", "path_mitsuba"})
#: the drivers a user can ask for
DRIVERS = ("auto", "megakernel", "wavefront")
LOCAL_SIZE = 64              # one fixed work-group size: every new one costs PoCL a fresh compile
MAX_WAVE_SLOTS = 1 << 17     # paths in flight at once in the wavefront (device memory: ~300 bytes each)
TARGET_LAUNCH_SECONDS = 0.2  # passes are sized to about this: keeps progress, Ctrl-C and time limits responsive


def _round_up(n: int) -> int:
    return max(LOCAL_SIZE, -(-n // LOCAL_SIZE) * LOCAL_SIZE)


def choose_driver(driver: str, integrator: str, count_rays: bool = False) -> str:
    """The driver that runs `integrator`: ``auto`` picks the megakernel, still the faster of the two on every device
    measured (benchmarks/README.md, "Wavefront"); ``wavefront`` is refused for integrators it does not run."""
    if driver not in DRIVERS:
        raise DriverError(f"unknown driver {driver!r}: expected one of {', '.join(DRIVERS)}")
    if driver == "auto":
        return "megakernel"
    if driver == "wavefront":
        if integrator not in WAVEFRONT_INTEGRATORS:
            raise DriverError(f"the wavefront driver runs the path integrators ({', '.join(sorted(WAVEFRONT_INTEGRATORS))}"
                             f" kernels), not {integrator!r}: use --driver megakernel")
        if count_rays:
            raise DriverError("ray counts come from the megakernel: count rays with --driver megakernel")
    return driver


#: how the film turns samples into pixels: "splat" (kernels/splat.cl: Mitsuba's and Nori's film, each sample
#: weighted into every pixel within the filter's radius), "sampling" (render.cl: filter importance sampling, each
#: sample in one pixel), "auto" (splat wherever it can run)
RECONSTRUCTIONS = ("auto", "splat", "sampling")


def choose_reconstruction(reconstruction: str, driver: str, count_rays: bool, reach: int,
                          feature_aovs: bool = False) -> bool:
    """Whether the film splats. Both give the same expected image; splatting has less noise per pixel with a wide
    filter (about a third of the variance with Mitsuba's default Gaussian) and correlates neighbouring pixels.
    ``auto`` splats where the filter reaches past its pixel (`reach` > 0: not a box), with the megakernel,
    without ray counting and without feature AOVs: those are for denoising, and Open Image Denoise takes each
    pixel's noise to be its own (a 4-spp splatted Cornell box came out of it as noisy as it went in:
    tests/test_denoise.py).
    ``splat`` is refused where it cannot run. A Mitsuba film with ``sample_border`` splats too, its samples drawn in
    a border of the filter's reach around the window as well (kernels/splat.cl CLR_SPLAT_BORDER), as Mitsuba's film
    does: it had sampled the filter, with about 3.4 times the per-pixel variance of Mitsuba's at a default Gaussian
    (issue 24: 1.83x the noise on BachelorThesis' texture-scanner scenes)."""
    if reconstruction not in RECONSTRUCTIONS:
        raise DriverError(f"unknown film reconstruction {reconstruction!r}: expected one of "
                          f"{', '.join(RECONSTRUCTIONS)}")
    if reconstruction == "auto":
        return driver == "megakernel" and not count_rays and not feature_aovs and reach > 0
    if reconstruction == "splat":
        if driver == "wavefront":
            raise DriverError("the wavefront driver samples the filter: a splatting film renders with "
                              "--driver megakernel")
        if count_rays:
            raise DriverError("rays are counted with a filter-sampling film (--reconstruction sampling)")
        return True
    return False


class MegakernelExecutor:
    """render_pass over launches of up to `launch_pixels` pixels (render_list over a list of pixels; render_spans over
    a list whose pixels each have their own samples)."""

    name = "megakernel"
    #: launch_spans: each listed pixel with its own samples in one launch (adaptive sampling's rounds)
    spans = True

    def __init__(self, ctx, queue, program, scene_bufs, camera, filter_cdf, launch_pixels):
        import pyopencl as cl

        from .device.kernelargs import KernelArgs

        self.queue = queue
        self.kernel = cl.Kernel(program, "render_pass")
        self.args = KernelArgs(self.kernel).set_scene(scene_bufs)
        self.args.set(cam=camera, filter_cdf=filter_cdf)
        self.list_kernel = cl.Kernel(program, "render_list")
        self.list_args = KernelArgs(self.list_kernel).set_scene(scene_bufs)
        self.list_args.set(cam=camera, filter_cdf=filter_cdf)
        self.spans_kernel = cl.Kernel(program, "render_spans")
        self.spans_args = KernelArgs(self.spans_kernel).set_scene(scene_bufs)
        self.spans_args.set(cam=camera, filter_cdf=filter_cdf)
        # at least PoCL's generic width: one compiled work-group function whatever the image size
        self.global_size = max(MIN_GENERIC_GLOBAL, _round_up(launch_pixels))

    def bind(self, film: dict) -> None:
        """The film's accumulator buffers, by their names in layout.FILM_ACCUMULATORS."""
        self.args.set(**film)
        self.list_args.set(**film)
        self.spans_args.set(**film)

    def warm(self) -> None:
        """A launch that adds no samples: PoCL compiles the work-group function at the first launch of a shape."""
        self.launch(0, 1, 0, 0, 0)

    def warm_list(self, pixel_list) -> None:
        """warm() for render_list and render_spans (only adaptive renders launch them, so only they pay their
        first-launch compile)."""
        self.launch(0, 0, 0, 0, 0, pixel_list=pixel_list)
        self.launch_spans(0, 0, pixel_list, pixel_list, 0)   # (no entry read: any buffer does for spans)

    def launch_spans(self, off: int, count: int, pixel_list, spans, seed: int) -> None:
        """The pixels pixel_list[off .. off + count - 1], entry i with its own samples: spans[i] = (first sample,
        number of samples), two uint32 each (kernels/render.cl render_spans)."""
        import numpy as np
        import pyopencl as cl

        self.spans_args.set(pixel_list=pixel_list, spans=spans, pixel_offset=np.uint32(off),
                            pixel_count=np.uint32(count), seed=np.uint32(seed))
        cl.enqueue_nd_range_kernel(self.queue, self.spans_kernel, (self.global_size,), (LOCAL_SIZE,))

    def launch(self, off: int, count: int, sample_offset: int, spp: int, seed: int, pixel_list=None) -> None:
        """Pixels off .. off + count - 1, or with `pixel_list` (a device buffer of pixel indices) the pixels
        pixel_list[off .. off + count - 1]."""
        import numpy as np
        import pyopencl as cl

        kernel, args = (self.kernel, self.args) if pixel_list is None else (self.list_kernel, self.list_args)
        if pixel_list is not None:
            args.set(pixel_list=pixel_list)
        args.set(pixel_offset=np.uint32(off), pixel_count=np.uint32(count),
                 sample_offset=np.uint32(sample_offset), spp=np.uint32(spp), seed=np.uint32(seed))
        cl.enqueue_nd_range_kernel(self.queue, kernel, (self.global_size,), (LOCAL_SIZE,))


class WavefrontExecutor:
    """wavefront.cl's stages. `stage_seconds` adds up the time of each stage when `timed` (each stage then waits
    for the device: for benchmarks/profile_wavefront.py, not for renders)."""

    name = "wavefront"
    STAGES = ("camera", "trace", "shade", "shadow", "compact", "finish", "flush")

    def __init__(self, ctx, queue, program, scene_bufs, camera, filter_cdf, launch_pixels, timed: bool = False):
        import numpy as np
        import pyopencl as cl

        from .device.kernelargs import KernelArgs

        self.ctx, self.queue = ctx, queue
        self.k = {s: cl.Kernel(program, f"wf_{s}") for s in self.STAGES}
        self.a = {s: KernelArgs(k) for s, k in self.k.items()}
        for s in ("camera", "trace", "shade", "shadow", "finish"):
            self.a[s].set_scene(scene_bufs)
        self.a["camera"].set(cam=camera, filter_cdf=filter_cdf)
        sizes = np.zeros(4, np.uint32)
        mf = cl.mem_flags
        d_sizes = cl.Buffer(ctx, mf.WRITE_ONLY, sizes.nbytes)
        probe = cl.Kernel(program, "wf_sizes")
        probe.set_arg(0, d_sizes)
        cl.enqueue_nd_range_kernel(queue, probe, (1,), None)
        cl.enqueue_copy(queue, sizes, d_sizes)
        path_bytes, sampler_bytes, hit_bytes, self.lanes = (int(x) for x in sizes[:4])
        self.launch_pixels = launch_pixels
        self.slots = max(MAX_WAVE_SLOTS, launch_pixels)
        n = self.slots
        rw = mf.READ_WRITE
        self.paths = cl.Buffer(ctx, rw, n * path_bytes)
        self.samplers = cl.Buffer(ctx, rw, n * sampler_bytes)
        self.hits = cl.Buffer(ctx, rw, n * hit_bytes)
        self.wt = cl.Buffer(ctx, rw, n * 8)
        self.queues = [cl.Buffer(ctx, rw, n * 4) for _ in range(3)]   # trace now, trace next, shadow
        self.flags = cl.Buffer(ctx, rw, n * 4)   # what each path needs next (wf_compact queues it)
        self.counts = cl.Buffer(ctx, rw, 16)
        self._no_list = cl.Buffer(ctx, rw, 4)   # bound to pixel_list when a launch runs over a range
        self._counts = np.zeros(4, np.uint32)
        zeros = np.zeros((launch_pixels, 4), np.float32)
        self.sum0 = cl.Buffer(ctx, rw | mf.COPY_HOST_PTR, hostbuf=zeros)
        self.sum1 = cl.Buffer(ctx, rw | mf.COPY_HOST_PTR, hostbuf=zeros)
        self.nbad = cl.Buffer(ctx, rw | mf.COPY_HOST_PTR, hostbuf=np.zeros(launch_pixels, np.uint32))
        self.device_bytes = n * (path_bytes + sampler_bytes + hit_bytes + 8 + 16) + launch_pixels * 36
        stride = np.uint32(n)   # slots per buffer: a column's length in the structure-of-arrays form (WF_SOA)
        self.a["camera"].set(paths=self.paths, samplers=self.samplers, stride=stride, wt=self.wt, flags=self.flags)
        self.a["trace"].set(paths=self.paths, hits=self.hits, stride=stride)
        self.a["shade"].set(paths=self.paths, samplers=self.samplers, hits=self.hits, stride=stride, flags=self.flags)
        self.a["compact"].set(flags=self.flags, shadow_queue=self.queues[2], counts=self.counts)
        self.a["shadow"].set(paths=self.paths, stride=stride, queue=self.queues[2])
        self.a["finish"].set(paths=self.paths, stride=stride, wt=self.wt, sum0=self.sum0, sum1=self.sum1,
                             nbad=self.nbad)
        self.a["flush"].set(sum0=self.sum0, sum1=self.sum1, nbad=self.nbad)
        self.timed = timed
        self.stage_seconds = dict.fromkeys(self.STAGES, 0.0)
        self.bounces = 0
        self.waves = 0

    def warm(self, stages=None) -> None:
        """Launch every stage (or those named) over no work: PoCL compiles a kernel's work-group function at its
        first launch."""
        import numpy as np
        import pyopencl as cl

        zero = np.uint32(0)
        self.a["camera"].set(pixel_list=self._no_list, listed=zero, pixel_offset=zero, n_slots=zero, k=np.uint32(1),
                             sample_offset=zero, seed=zero)
        self.a["trace"].set(queue=self.queues[0], n=zero)
        self.a["shade"].set(queue=self.queues[0], n=zero)
        self.a["compact"].set(queue=self.queues[0], identity=zero, n=zero, next_queue=self.queues[1])
        self.a["shadow"].set(n=zero)
        self.a["finish"].set(n_pixels=zero, k=np.uint32(1))
        self.a["flush"].set(pixel_list=self._no_list, listed=zero, pixel_offset=zero, n_pixels=zero, spp=zero)
        for s in stages or self.STAGES:
            cl.enqueue_nd_range_kernel(self.queue, self.k[s], (LOCAL_SIZE,), (LOCAL_SIZE,))
        self.queue.finish()

    def warm_list(self, pixel_list) -> None:
        """Nothing to do: launches over a list run the very stage kernels that warm() compiled."""

    def bind(self, film: dict) -> None:
        """The film's accumulator buffers, by their names in layout.FILM_ACCUMULATORS (wf_flush adds to them)."""
        self.a["flush"].set(**film)

    def _run(self, stage: str, n: int) -> None:
        import time

        import pyopencl as cl

        t0 = time.perf_counter() if self.timed else 0.0
        cl.enqueue_nd_range_kernel(self.queue, self.k[stage], (_round_up(n),), (LOCAL_SIZE,))
        if self.timed:
            self.queue.finish()
            self.stage_seconds[stage] += time.perf_counter() - t0

    def _take_counts(self) -> tuple[int, int]:
        """The queue sizes the last camera or shade stage left, and the counters zeroed for the next one."""
        import numpy as np
        import pyopencl as cl

        cl.enqueue_copy(self.queue, self._counts, self.counts)   # blocking
        n_next, n_shadow = int(self._counts[0]), int(self._counts[1])
        cl.enqueue_fill_buffer(self.queue, self.counts, np.uint32(0), 0, 16)
        return n_next, n_shadow

    def launch(self, off: int, count: int, sample_offset: int, spp: int, seed: int, pixel_list=None) -> None:
        """As MegakernelExecutor.launch."""
        import numpy as np
        import pyopencl as cl

        listing = dict(pixel_list=self._no_list if pixel_list is None else pixel_list,
                       listed=np.uint32(pixel_list is not None))
        self.a["camera"].set(**listing)
        self.a["flush"].set(**listing)
        cl.enqueue_fill_buffer(self.queue, self.counts, np.uint32(0), 0, 16)
        k_max = max(1, self.slots // count)
        done = 0
        while done < spp:
            k = min(k_max, spp - done)
            n_slots = count * k
            q_now, q_next = self.queues[0], self.queues[1]
            self.a["camera"].set(pixel_offset=np.uint32(off), n_slots=np.uint32(n_slots),
                                 k=np.uint32(k), sample_offset=np.uint32(sample_offset + done),
                                 seed=np.uint32(seed))
            self._run("camera", n_slots)
            self.a["compact"].set(queue=q_next, identity=np.uint32(1), n=np.uint32(n_slots), next_queue=q_now)
            self._run("compact", n_slots)
            n, _ = self._take_counts()
            while n > 0:
                self.a["trace"].set(queue=q_now, n=np.uint32(n))
                self._run("trace", n)
                self.a["shade"].set(queue=q_now, n=np.uint32(n))
                self._run("shade", -(-n // self.lanes))   # a shade work-item takes `lanes` paths (WF_LANES)
                self.a["compact"].set(queue=q_now, identity=np.uint32(0), n=np.uint32(n), next_queue=q_next)
                self._run("compact", n)
                n_next, n_shadow = self._take_counts()
                if n_shadow:
                    self.a["shadow"].set(n=np.uint32(n_shadow))
                    self._run("shadow", n_shadow)
                self.bounces += 1
                q_now, q_next = q_next, q_now
                n = n_next
            self.a["finish"].set(n_pixels=np.uint32(count), k=np.uint32(k))
            self._run("finish", count)
            self.waves += 1
            done += k
        self.a["flush"].set(pixel_offset=np.uint32(off), n_pixels=np.uint32(count), spp=np.uint32(spp))
        self._run("flush", count)


class SplatExecutor:
    """kernels/splat.cl: a splatting film. A pass renders every sample of the pixels within the filter's reach of
    the pass's pixels into a record buffer (render_records, in launches of `launch_pixels`), then adds each pixel's
    neighbourhood to its sums (splat_gather). A band of pixels (a cluster task) renders its halo's samples too (the
    same samples: random numbers are keyed by pixel and sample), so its sums are the one-process film's. With
    `border` (Mitsuba's sample_border: the filter's reach) the records cover a grid of (width + 2 border) x
    (height + 2 border) pixels around the window (kernels/splat.cl CLR_SPLAT_BORDER); `halo` and the record counts are
    in that grid, the gathered pixels in the window's.

    Adaptive sampling's launches (`launch`, `launch_spans`: pixels with counts of their own) go to a store instead,
    each pixel's splats kept apart (3 (2 reach + 1)^2 float4 per pixel, store_buffer_bytes), and `resolve` turns it
    into the film's sums, each pixel's splats weighed by 1 / its samples (kernels/splat.cl store_pixel,
    splat_resolve)."""

    name = "megakernel"
    #: the record buffer of a pass stays below this (its samples per pixel are cut to fit)
    MAX_RECORD_BYTES = 256 << 20
    #: launch_spans: each listed pixel with its own samples in one launch (adaptive sampling's rounds)
    spans = True

    def __init__(self, ctx, queue, program, scene_bufs, camera, width, height, reach, launch_pixels, border=0):
        import pyopencl as cl

        from .device.kernelargs import KernelArgs

        self.ctx, self.queue = ctx, queue
        self.width, self.height, self.reach, self.border = width, height, reach, border
        self.grid_width, self.grid_height = width + 2 * border, height + 2 * border   # the records' pixels
        self.records = KernelArgs(cl.Kernel(program, "render_records")).set_scene(scene_bufs).set(cam=camera)
        self.gather = KernelArgs(cl.Kernel(program, "splat_gather")).set(cam=camera)
        self.store_range = KernelArgs(cl.Kernel(program, "store_pass")).set_scene(scene_bufs).set(cam=camera)
        self.store_list = KernelArgs(cl.Kernel(program, "store_spans")).set_scene(scene_bufs).set(cam=camera)
        self.resolver = KernelArgs(cl.Kernel(program, "splat_resolve")).set(cam=camera)
        self.launch_pixels = launch_pixels
        self.global_size = max(MIN_GENERIC_GLOBAL, _round_up(launch_pixels))
        self._buf, self._buf_samples = None, 0
        self._store = None         # (store, counts): allocated by the first adaptive render
        self._stored = False       # samples went to the store since the film was bound: resolve before reading

    def halo(self, p0: int, p1: int) -> tuple[int, int]:
        """The record pixels whose samples reach pixels p0 .. p1 - 1: whole rows of the records' grid, `reach`
        above and below."""
        w, g, b = self.width, self.grid_width, self.border
        return (max(0, (p0 // w + b - self.reach) * g),
                min(g * self.grid_height, ((p1 - 1) // w + b + 1 + self.reach) * g))

    @property
    def device_bytes(self) -> int:
        """The record buffers' bytes as allocated now (they grow to the largest pass, at most MAX_RECORD_BYTES), and
        the store's once an adaptive render made it."""
        return self._buf_samples * self.record_bytes() + (0 if self._store is None else sum(self.store_buffer_bytes()))

    def record_bytes(self) -> int:
        """Bytes a sample's record takes: its radiance and its 2 (2 reach + 1) filter weights."""
        return 16 + 8 * (2 * self.reach + 1)

    def max_spp(self, p0: int, p1: int) -> int:
        """The most samples per pixel a pass of pixels p0 .. p1 - 1 takes: its records fit MAX_RECORD_BYTES, or
        those of one row and its halo (larger bands are then cut into chunks of rows, run_pass)."""
        h0, h1 = self.halo(p0, p1)
        least = min(h1 - h0, self.grid_width * (1 + 2 * self.reach))
        return max(1, self.MAX_RECORD_BYTES // (self.record_bytes() * least))

    def _chunk_pixels(self, spp: int) -> int:
        """Pixels per chunk of a pass so that a chunk's records, halo included, fit MAX_RECORD_BYTES."""
        rows = self.MAX_RECORD_BYTES // (self.record_bytes() * spp * self.grid_width) - 2 * self.reach
        return max(1, rows) * self.width

    def bind(self, film: dict) -> None:
        accumulators = {k: v for k, v in film.items() if k != "rays"}   # all but the ray counters' dummy
        self.gather.set(**accumulators)
        self.resolver.set(**accumulators)
        self._stored = False
        if self._store is not None:
            self._clear_store()

    # -- adaptive sampling's store ---------------------------------------------------------------------------
    def store_buffer_bytes(self) -> list[int]:
        """Device bytes of the store's buffers: layout's SPLAT_STORE_ENTRIES float4 per splat, (2 reach + 1)^2 splats
        per pixel; a pixel's counts (two uint)."""
        n = self.width * self.height
        return [16 * layout.ENUMS["SPLAT_STORE_ENTRIES"] * n * (2 * self.reach + 1) ** 2, 8 * n]

    def _clear_store(self) -> None:
        import pyopencl as cl

        for buf in self._store:
            cl.enqueue_fill_buffer(self.queue, buf, np.uint32(0), 0, buf.size)

    def _use_store(self) -> None:
        import pyopencl as cl

        if self._store is None:
            mf = cl.mem_flags.READ_WRITE
            self._store = tuple(cl.Buffer(self.ctx, mf, size) for size in self.store_buffer_bytes())
            self._clear_store()
            store, counts = self._store
            for k in (self.store_range, self.store_list, self.resolver):
                k.set(store=store, counts=counts)
        self._stored = True

    def warm_list(self, pixel_list) -> None:
        """The store's kernels' first launches (only adaptive renders use them, so only they pay that compile)."""
        self._use_store()
        self.launch(0, 0, 0, 0, 0)
        self.launch_spans(0, 0, pixel_list, pixel_list, 0)   # (no entry read: any buffer does for spans)
        self.resolve()

    def launch(self, off: int, count: int, sample_offset: int, spp: int, seed: int, pixel_list=None) -> None:
        """Samples sample_offset .. + spp - 1 of pixels off .. off + count - 1 into the store."""
        import pyopencl as cl

        if pixel_list is not None:
            raise DriverError("a splatting film's pixel lists are launched with their spans (launch_spans)")
        self._use_store()
        self.store_range.set(pixel_offset=np.uint32(off), pixel_count=np.uint32(count),
                             sample_offset=np.uint32(sample_offset), spp=np.uint32(spp), seed=np.uint32(seed))
        cl.enqueue_nd_range_kernel(self.queue, self.store_range.kernel, (self.global_size,), (LOCAL_SIZE,))

    def launch_spans(self, off: int, count: int, pixel_list, spans, seed: int) -> None:
        """MegakernelExecutor.launch_spans' samples into the store."""
        import pyopencl as cl

        self._use_store()
        self.store_list.set(pixel_list=pixel_list, spans=spans, pixel_offset=np.uint32(off),
                            pixel_count=np.uint32(count), seed=np.uint32(seed))
        cl.enqueue_nd_range_kernel(self.queue, self.store_list.kernel, (self.global_size,), (LOCAL_SIZE,))

    def resolve(self, normalise: bool = True) -> None:
        """The film's sums from the store, if samples went there since the film was bound (before reading it)."""
        import pyopencl as cl

        if not self._stored:
            return
        n = self.width * self.height
        for off in range(0, max(n, 1), self.launch_pixels):
            self.resolver.set(pixel_offset=np.uint32(off), pixel_count=np.uint32(min(self.launch_pixels, n - off)),
                              normalise=np.uint32(normalise))
            cl.enqueue_nd_range_kernel(self.queue, self.resolver.kernel, (self.global_size,), (LOCAL_SIZE,))

    def settle(self) -> None:
        """When every pixel holds the same count: the store's splats become the film's sums as a uniform render's
        (unweighted), so that run_pass's records and gathers add the rest (adaptive sampling's switch to a uniform
        render, at the uniform film's cost per sample); the store is not read again until the film is bound."""
        self.resolve(normalise=False)
        self._stored = False

    def warm(self) -> None:
        self._buffer(1)
        self._launch(self.records, 0, 0, 0, 0, 0, rec_base=np.uint32(0))
        self._launch(self.gather, 0, 0, 0, 0, 0, rec_base=np.uint32(0), rec_first=np.uint32(0),
                     rec_stop=np.uint32(0))

    def _buffer(self, samples: int) -> None:
        """Record buffers for at least `samples` samples."""
        import pyopencl as cl

        if samples > self._buf_samples:
            mf = cl.mem_flags.READ_WRITE
            self._buf = (cl.Buffer(self.ctx, mf, 16 * samples),
                         cl.Buffer(self.ctx, mf, (self.record_bytes() - 16) * samples))
            self._buf_samples = samples
            for k in (self.records, self.gather):
                k.set(records=self._buf[0], weights=self._buf[1])

    def _launch(self, k, off, count, sample_offset, spp, seed, **extra) -> None:
        import pyopencl as cl

        k.set(pixel_offset=np.uint32(off), pixel_count=np.uint32(count), sample_offset=np.uint32(sample_offset),
              spp=np.uint32(spp), seed=np.uint32(seed), **extra)
        cl.enqueue_nd_range_kernel(self.queue, k.kernel, (self.global_size,), (LOCAL_SIZE,))

    def run_pass(self, p0: int, p1: int, sample_offset: int, spp: int, seed: int) -> int:
        """Enqueue one pass of `spp` samples (at most max_spp) over pixels p0 .. p1 - 1; returns its launches. A
        band whose records would not fit is cut into chunks of rows, each rendering its own halo: the records
        are the same samples, so every pixel's sums are the same."""
        launches = 0
        step = self._chunk_pixels(spp)
        for c0 in range(p0, p1, step):
            c1 = min(p1, c0 + step)
            h0, h1 = self.halo(c0, c1)
            self._buffer(spp * (h1 - h0))
            for off in range(h0, h1, self.launch_pixels):
                self._launch(self.records, off, min(self.launch_pixels, h1 - off), sample_offset, spp, seed,
                             rec_base=np.uint32(h0))
                launches += 1
            for off in range(c0, c1, self.launch_pixels):
                self._launch(self.gather, off, min(self.launch_pixels, c1 - off), sample_offset, spp, seed,
                             rec_base=np.uint32(h0), rec_first=np.uint32(h0), rec_stop=np.uint32(h1))
                launches += 1
        return launches
