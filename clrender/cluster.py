"""Render on a Dask cluster: tasks of sample ranges (and bands of rows for large films) on many workers,
whose accumulators the client adds in a fixed order.

    import clrender
    film = clrender.render(scene, spp=1024, seed=0, cluster="local:4")          # a LocalCluster of 4
    film = clrender.render(scene, spp=1024, cluster="tcp://head:8786")            # `dask scheduler` there
    film = clrender.render("scene.xml", spp=1024, cluster=client, files="shared")  # a distributed.Client

How the scene reaches the workers (``files=``):
  ``"ship"``   (default) the client loads and packs the scene once (BVH included) and scatters the packed
               tables to the workers: they need no scene files. Best for scenes up to some hundred MB
               packed, or when workers do not share a filesystem with the client.
  ``"shared"`` the task names the XML file (absolute path), the ``-D`` defines and the dialect; each worker
               loads the scene from that path and builds its own BVH, after checking that the files it
               reads hash like the client's. Best for very large meshes on a farm with a shared filesystem.
Either way a worker builds its program once per scene and device and keeps it (keyed by the scene's
content hash) for every later task of that scene (the worker side: cluster_worker.py).

Samples are numbered globally and the counter-based RNG makes a sample's value independent of where it is
drawn, so any split gives the single-process image up to the float rounding of the sums. Dask reruns the
task of a worker that died (and the client sends a shipped scene again if that worker held its last copy);
a worker whose device fails is reported by name and its task moves to the other workers.
"""
from __future__ import annotations

import copy
import os
import time
from pathlib import Path

from .cluster_worker import ShippedScene, SharedScene, TaskFailed, render_task
from .errors import ClrenderError
from .scene.dialect import resolve as resolve_dialect
from .scenesource import SceneSource, packed_hash

INSTALL_HINT = 'rendering on a cluster needs Dask: pip install "clrender[cluster]"'
MIN_BAND_PIXELS = 1 << 16   # one launch: a band smaller than this wastes a GPU
TASK_SECONDS = 2.0          # adaptive task size: long enough to hide the per-task cost, short enough that
                            # Ctrl-C, --time-limit and the progress bar respond and the load balances
FIRST_TASK_SPP = 2          # the first tasks measure the speed of the workers
MAX_DEVICE_FAILURES = 3     # per task, before the render gives up


class ClusterError(ClrenderError):
    """The cluster render failed (no workers, a bad scene on a worker, every device failed, ...)."""


def _distributed():
    try:
        import distributed
    except ImportError:
        raise ClusterError(INSTALL_HINT) from None
    return distributed


def usable_device_specs() -> list[str]:
    """One spec per device worth a LocalCluster worker: the default (CPU) device once, plus every GPU or
    accelerator that compiles kernels. Other CPU devices are the same cores again and are left out."""
    import pyopencl as cl

    from .device.context import build_check, choose_device, list_devices

    devices = list_devices()
    try:
        d_def = choose_device(None)[1]
    except ClrenderError:
        d_def = None
    specs = []
    for i, (p, d) in enumerate(devices):
        if d_def is not None and d.int_ptr == d_def.int_ptr:
            specs.insert(0, str(i))
        elif not d.type & cl.device_type.CPU and build_check(p, d) is None:
            specs.append(str(i))
    return specs or [None]


def connect(cluster, n_workers: int | None = None):
    """(client, close, description, is_local) for a cluster given as a distributed.Client, a Cluster object,
    "local" / "local:N", a scheduler address ("tcp://HOST:PORT") or a scheduler file."""
    distributed = _distributed()
    if isinstance(cluster, distributed.Client):
        return cluster, (lambda: None), f"Dask client {cluster.scheduler.address}", False
    if hasattr(cluster, "scheduler_address"):
        client = distributed.Client(cluster)
        return client, client.close, f"Dask cluster {cluster.scheduler_address}", False
    spec = str(cluster).strip()
    if spec == "local" or spec.startswith("local:"):
        n = n_workers
        if spec.startswith("local:"):
            try:
                n = int(spec[len("local:"):])
            except ValueError:
                n = 0
            if n < 1:
                raise ClusterError(f"--cluster {spec}: expected local or local:N with N >= 1 workers")
        import logging

        try:
            import bokeh  # noqa: F401
            dashboard = ":0"   # any free port: several renders (or users) may run at once
        except ImportError:
            dashboard = None
        # The scheduler lives in this process: its chatter (workers joining, leaving, restarted after a
        # crash) is not the user's business; what matters is reported by render().
        for name in ("distributed", "bokeh"):
            logging.getLogger(name).setLevel(logging.ERROR)
        lc = distributed.LocalCluster(n_workers=n or len(usable_device_specs()), threads_per_worker=1,
                                      processes=True, dashboard_address=dashboard,
                                      silence_logs=logging.CRITICAL)
        client = distributed.Client(lc)
        from .dask_plugins import IgnoreCtrlC

        client.register_plugin(IgnoreCtrlC(), name="clrender-ignore-ctrl-c")

        def close():
            client.close()
            lc.close()
        return client, close, f"local Dask cluster of {len(lc.workers)} worker processes", True
    try:
        if "://" in spec:
            client = distributed.Client(spec, timeout="20s")
        elif Path(spec).is_file():
            client = distributed.Client(scheduler_file=spec, timeout="20s")
        else:
            raise ClusterError(f"--cluster {spec!r}: expected local[:N], a scheduler address like "
                               "tcp://HOST:8786, or an existing scheduler file")
    except ClusterError:
        raise
    except (OSError, TimeoutError, ValueError) as exc:
        raise ClusterError(f"cannot reach the Dask scheduler {spec}: {exc}") from None
    return client, client.close, f"Dask scheduler {client.scheduler.address}", False


def _bands(width: int, height: int, n: int) -> list[tuple[int, int]]:
    rows = [height * j // n for j in range(n + 1)]
    return [(rows[j] * width, rows[j + 1] * width) for j in range(n)]


class TaskPlan:
    """Hands out tasks (index, (pixel0, pixel1), sample start, sample count) in index order: sample chunks
    outer, bands of rows inner, so a partial render has its samples spread over the whole image; results
    are added in index order.

    Bands are used only for films of several launches (one band per launch at most): a task returns its
    band of the film, where a sample chunk of a whole film returns the whole film, so bands keep the bytes
    sent back per sample small on big films. ``tasks=N`` fixes the split (N tasks, about equal); otherwise
    chunks start at FIRST_TASK_SPP samples and then grow to about TASK_SECONDS of the measured speed."""

    def __init__(self, width, height, spp, start_sample, threads, tasks=None, bands=None):
        pixels = width * height
        if bands is None:
            bands = min(max(tasks or 4 * threads, 1), max(pixels // MIN_BAND_PIXELS, 1))
        self.bands = _bands(width, height, max(1, min(int(bands), height)))
        self.spp, self.start = spp, start_sample
        self.fixed = None
        if tasks is not None:
            chunks = max(1, min(spp, -(-int(tasks) // len(self.bands))))
            self.fixed = [spp * (i + 1) // chunks - spp * i // chunks for i in range(chunks)]
        self.done_spp = 0          # samples per pixel handed out in whole chunks
        self.queue: list = []      # tasks of the current chunk not yet handed out
        self.issued = self.chunks = 0
        self.rates: list[float] = []

    def observe(self, pixels: int, count: int, seconds: float) -> None:
        if seconds > 0:
            self.rates = (self.rates + [pixels * count / seconds])[-16:]

    def _chunk(self, threads: int) -> int:
        left = self.spp - self.done_spp
        if self.fixed is not None:
            return self.fixed[self.chunks]
        if not self.rates:
            c = FIRST_TASK_SPP
        else:
            rate = sorted(self.rates)[len(self.rates) // 2]    # pixel-samples per second of one task
            band = max(p1 - p0 for p0, p1 in self.bands)
            c = int(TASK_SECONDS * rate / band)
            # near the end, smaller chunks so that every thread has something to do
            c = min(c, -(-left * len(self.bands) // max(threads, 1)))
        return max(1, min(c, left))

    def next(self, threads: int):
        if not self.queue:
            if self.done_spp >= self.spp:
                return None
            c = self._chunk(threads)
            s0 = self.start + self.done_spp
            self.queue = [(p, s0, c) for p in self.bands]
            self.done_spp += c
            self.chunks += 1
        pixels, s0, c = self.queue.pop(0)
        self.issued += 1
        return (self.issued - 1, pixels, s0, c)

    @property
    def exhausted(self) -> bool:
        return not self.queue and self.done_spp >= self.spp


def _payload(scene, files, defines, dialect, say):
    """(payload, scene key, width, height, default spp, integrator) for a Scene or an XML path."""
    from .pack import pack_scene

    if isinstance(scene, (str, Path)):
        source = SceneSource(str(Path(scene).resolve()), dict(defines or {}), resolve_dialect(dialect))
        key = source.content_hash()
        loaded = source.load()
    else:
        if files == "shared":
            raise ClusterError("files='shared' needs the scene as a path to its XML file (workers load it)")
        source, key, loaded = None, None, scene
    w, h, spp, integ = loaded.width, loaded.height, loaded.sample_count, loaded.integrator.kernel
    if files == "shared":
        return SharedScene(key, source), key, w, h, spp, integ
    if files != "ship":
        raise ClusterError(f"files={files!r}: expected 'ship' or 'shared'")
    buffers = pack_scene(loaded)
    if key is None:
        key = packed_hash(buffers, integ, w, h)
    from .renderer import samples_border

    return ShippedScene(key, buffers, integ, w, h, spp, samples_border(loaded)), key, w, h, spp, integ


def render(scene, spp: int | None = None, seed: int = 0, cluster="local", *, start_sample: int = 0,
           files: str = "ship", defines: dict | None = None, dialect: str | None = None,
           device=None, tasks: int | None = None, bands: int | None = None, time_limit: float | None = None,
           progress: bool = False, say=None, on_result=None, partial=None, driver: str = "auto",
           reconstruction: str = "auto"):
    """Render on a Dask cluster and return the Film (``film.count`` holds the true per-pixel counts).

    ``scene``: a loaded Scene (shipped) or the path of its XML file (shipped or, with ``files="shared"``,
    loaded by the workers). ``cluster``: see :func:`connect`. ``device``: one device spec for every worker
    (default: each worker's own choice, ``CLRENDER_DEVICE`` in its environment, or for a LocalCluster one
    usable device per worker). ``tasks``: how many tasks (default 4 per worker thread). ``say``: called
    with progress messages. ``on_result(result, client)``: called after every finished task (tests).
    Ctrl-C cancels the outstanding tasks and returns what was finished; ``time_limit`` stops handing out
    tasks after that many seconds. ``partial=(seconds, callback)``: while tasks are outstanding, every that
    many seconds, ``callback`` gets the film of the tasks finished so far (true per-pixel counts, metadata
    ``partial`` set), so a killed client leaves its work behind. ``driver``: how workers run passes
    (clrender/executors.py; both give the same image); ``reconstruction``: the film's (Renderer's argument;
    a splatting film's bands render their halo's samples too, so the image is the one-process film's).
    """
    from .interrupt import PassFlag as _SigintFlag
    from .renderer import RenderStats

    say = say or (lambda msg: None)
    # A loaded Scene knows the dialect it was read in; a path is read in `dialect` (None: $CLRENDER_NORI_DIALECT,
    # else upstream), by the client and by every worker alike.
    dialect = getattr(scene, "nori_dialect", None) or resolve_dialect(dialect)
    client, close, what, local = connect(cluster)
    try:
        return _render(client, what, local, scene, spp, seed, start_sample, files, defines, dialect, device,
                       tasks, bands, time_limit, progress, say, on_result, partial, RenderStats, _SigintFlag, driver,
                       reconstruction)
    finally:
        close()


def _render(client, what, local, scene, spp, seed, start_sample, files, defines, dialect, device, n_tasks, bands,
            time_limit, progress, say, on_result, partial, RenderStats, SigintFlag, driver="auto",
            reconstruction="auto"):
    from .version import __version__
    from .parts import Accumulator

    distributed = _distributed()
    t_begin = time.perf_counter()
    payload, key, width, height, scene_spp, integrator = _payload(scene, files, defines, dialect, say)
    spp = int(spp if spp is not None else scene_spp)
    if spp < 1:
        raise ValueError("spp must be at least 1")
    _wait_for_a_worker(client, what)
    threads, threads_at = _threads(client), time.perf_counter()
    say(f"{what}: {len(client.scheduler_info()['workers'])} workers, {threads} threads")
    link = _dashboard(client)
    say(f"Dask dashboard: {link}" if link else "no Dask dashboard (it needs bokeh: pip install bokeh)")
    plan = device if device is not None else (usable_device_specs() if local else None)
    plan = plan if plan != [None] else None
    shipped = payload if files == "ship" else None

    def send_scene():
        # Broadcast, but Dask's active memory manager soon drops the copies that no waiting task needs, down
        # to one: a dead worker can still take the scene with it (then it is sent again, see below).
        _wait_for_a_worker(client, what)
        return client.scatter(shipped, broadcast=True, hash=False)

    if shipped is not None:
        payload = send_scene()
    lost_in_a_row = 0                  # scene losses since the last finished task
    plan_tasks = TaskPlan(width, height, spp, start_sample, threads, n_tasks, bands)
    acc = Accumulator(width, height)
    n_pixels = width * height
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=spp * n_pixels, unit="sample", unit_scale=True, dynamic_ncols=True, leave=True,
                   desc=f"rendering on {len(client.scheduler_info()['workers'])} workers")
    pending: dict = {}                 # future -> (task, the scene future it depends on or None)
    failures: dict[int, int] = {}      # task index -> device failures
    bad_workers: set[str] = set()
    held: dict[int, dict] = {}         # finished results waiting for their turn in the fixed order
    added, next_add = [], 0
    devices, workers_used = set(), set()
    stopped_by = None
    stats = RenderStats()

    def submit(task, workers=None):
        index, pixels, s0, cnt = task
        f = client.submit(render_task, payload, index, pixels, s0, cnt, seed, plan, driver, reconstruction,
                          pure=False,
                          key=f"clrender-{key[:12]}-{seed}-{s0}-{pixels[0]}-{os.urandom(4).hex()}",
                          workers=workers, allow_other_workers=False)
        pending[f] = task, (payload if shipped is not None else None)

    def fail(msg):
        client.cancel(list(pending))
        pending.clear()
        raise ClusterError(msg)

    def film_of(acc, added, stats, complete, stopped_by, partial=False):
        """The Film of what `acc` holds (the tasks in `added`), with the render's metadata; fills in `stats`."""
        stats.samples = int(acc.count.sum())
        stats.passes = len(added)
        stats.dropped = int(acc.dropped.sum())
        stats.interrupted = stopped_by == "Ctrl-C"
        meta = {"spp": int(acc.count.min()) if n_pixels else 0, "spp_max": int(acc.count.max()) if n_pixels else 0,
                "seed": seed, "start_sample": start_sample, "render_seconds": round(stats.seconds, 4),
                "device": "; ".join(sorted(devices)), "integrator": integrator, "version": __version__,
                "interrupted": not complete, "dropped_samples": stats.dropped, "scene_hash": key,
                "dialect": dialect, "cluster": what, "workers": len(workers_used), "tasks": len(added),
                "bands": len(plan_tasks.bands), "wall_seconds": round(time.perf_counter() - t_begin, 4)}
        if stopped_by:
            meta["stopped_by"] = stopped_by
        if partial:
            meta["partial"] = True
        if acc.sum_w2 is not None:
            meta["film"] = "splat"
        film = acc.film(meta)
        film.stats = stats
        return film

    t_start = last_partial = time.perf_counter()
    with SigintFlag() as flag:
        try:
            while True:
                if time_limit is not None and time.perf_counter() - t_start >= time_limit and stopped_by is None:
                    stopped_by = "time limit"
                if time.perf_counter() - threads_at > 2.0:   # asking the scheduler costs a round trip
                    threads, threads_at = _threads(client), time.perf_counter()
                window = 2 * max(threads, 1)
                while stopped_by is None and len(pending) < window:
                    task = plan_tasks.next(threads)
                    if task is None:
                        break
                    submit(task)
                if not pending:
                    break
                try:
                    distributed.wait(list(pending), timeout=0.2, return_when="FIRST_COMPLETED")
                except Exception:  # a timeout, or futures cancelled under us (looked at one by one below)
                    pass
                for f in [f for f in pending if f.done()]:
                    task, sent = pending.pop(f)
                    r = None
                    if f.status == "finished":
                        try:
                            r = f.result()
                        except Exception:
                            # the worker holding the result died before we fetched it, and Dask could not
                            # compute it again (its scene went too): the status says what became of it
                            if f.status == "finished":
                                raise
                    if r is not None:
                        lost_in_a_row = 0
                        f.release()
                        if r["version"] != __version__:
                            fail(f"worker {r['worker']} runs clrender {r['version']}, this client "
                                 f"{__version__}: install the same version everywhere")
                        held[r["index"]] = r
                        plan_tasks.observe(task[1][1] - task[1][0], r["count"], r["seconds"])
                        devices.add(r["device"])
                        workers_used.add(r["worker"])
                        if bar is not None:
                            bar.update(r["count"] * (task[1][1] - task[1][0]))
                        if on_result is not None:
                            on_result(r, client)
                        continue
                    if f.status == "cancelled" and not flag.requested and sent is not None \
                            and sent.status != "finished":
                        # the scheduler forgot the scattered scene (its last copy was on a worker that died)
                        # and every task that needed it: not the task's fault. Send the scene again, once.
                        if sent is payload:
                            lost_in_a_row += 1
                            if lost_in_a_row > MAX_DEVICE_FAILURES:
                                fail(f"the cluster lost the scene data {lost_in_a_row} times without finishing "
                                     "a task in between (its workers keep dying)")
                            payload = send_scene()
                        submit(task)
                        continue
                    if f.status == "cancelled" and not flag.requested:
                        # not by us: the scheduler forgot it (its workers went away); hand it out again
                        failures[task[0]] = failures.get(task[0], 0) + 1
                        if failures[task[0]] >= MAX_DEVICE_FAILURES:
                            fail(f"task {task[0]} was cancelled by the cluster {failures[task[0]]} times")
                        submit(task)
                        continue
                    if f.status == "cancelled":
                        continue
                    exc = f.exception() if f.status == "error" else None
                    f.release()
                    if isinstance(exc, TaskFailed) and exc.args[0] == "device":
                        failures[task[0]] = failures.get(task[0], 0) + 1
                        bad_workers.add(exc.args[1])
                        good = [w for w in client.scheduler_info()["workers"] if w not in bad_workers]
                        say(f"device failure on {exc}; its task goes to another worker")
                        if failures[task[0]] >= MAX_DEVICE_FAILURES or not good:
                            fail(f"giving up: {exc} (failed {failures[task[0]]} time(s); "
                                 f"{len(good)} healthy worker(s) left)")
                        submit(task, workers=good)
                    elif isinstance(exc, TaskFailed):
                        fail(str(exc))
                    elif exc is not None and type(exc).__name__ == "KilledWorker":
                        fail(f"task {task[0]} (samples {task[2]}..{task[2] + task[3] - 1}) killed its workers "
                             f"too often: {exc}")
                    else:
                        fail(f"task {task[0]} failed on the cluster: {f.status}: {exc!r}")
                while next_add in held:    # add in index order as soon as the prefix is complete
                    _add(acc, held.pop(next_add), added)
                    next_add += 1
                if partial is not None and pending and time.perf_counter() - last_partial >= partial[0]:
                    # a copy with the out-of-order results added too: the render's own sums keep their order
                    snap, snap_added = copy.deepcopy(acc), list(added)
                    for index in sorted(held):
                        _add(snap, held[index], snap_added)
                    snap_stats = copy.copy(stats)
                    snap_stats.seconds = time.perf_counter() - t_start
                    partial[1](film_of(snap, snap_added, snap_stats, False, None, partial=True))
                    last_partial = time.perf_counter()
                if flag.requested and stopped_by is None:
                    stopped_by = "Ctrl-C"
                    client.cancel(list(pending))
                    pending.clear()
        finally:
            if bar is not None:
                bar.close()
    for index in sorted(held):             # after an interruption: the finished tasks, still in order
        _add(acc, held.pop(index), added)
    stats.seconds = time.perf_counter() - t_start
    complete = plan_tasks.exhausted and len(added) == plan_tasks.issued
    return film_of(acc, added, stats, complete, stopped_by)


def _wait_for_a_worker(client, what):
    try:
        client.wait_for_workers(1, timeout=60)
    except TimeoutError:
        raise ClusterError(f"no Dask worker joined {what} within 60 s (start some with `dask worker ADDRESS`)") \
            from None


def _add(acc, r, added):
    acc.add_raw(r["p0"], r["accumulators"])
    added.append(r["index"])


def _threads(client) -> int:
    return sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values())


def _dashboard(client) -> str | None:
    try:
        if "dashboard" not in client.scheduler_info().get("services", {}):
            return None
        return client.dashboard_link
    except Exception:  # the link is a nicety: never fail a render over it
        return None

