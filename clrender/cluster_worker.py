"""The worker side of cluster rendering (cluster.py is the client): what a task receives, the per-worker
cache of scenes and programs, and the task itself.

A worker keeps one Renderer (uploaded scene + built program) per scene content hash and device, so only
its first task of a scene pays for loading and building; tasks of a multi-threaded worker take turns on it.
Errors come back as TaskFailed naming the worker and device: "device" failures (no such device, a driver
error) let the client move the task elsewhere, "scene" failures (a broken scene, files that differ from
the client's) stop the render.
"""
from __future__ import annotations

import os
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass
from types import SimpleNamespace


from .errors import ClrenderError, DeviceError
from .scenesource import SceneSource

WORKER_CACHE_SCENES = 2     # packed scenes and programs a worker keeps


class TaskFailed(Exception):
    """Raised on a worker; args: (kind, worker, device, message). kind "device": the worker's device or
    driver failed (the task may run elsewhere); "scene": the scene cannot be rendered anywhere."""

    def __str__(self):
        kind, worker, device, message = self.args
        return f"worker {worker} ({device}): {message}"


# ---------------------------------------------------------------------------------------------- payloads
@dataclass(frozen=True)
class ShippedScene:
    """The packed scene itself: workers need no files."""
    key: str
    buffers: object
    integrator: str
    width: int
    height: int
    sample_count: int
    #: the film's sample_border (Mitsuba): the Renderer's film then draws samples around the window too
    #: (renderer.samples_border)
    sample_border: bool = False

    def scene(self):
        # What Renderer reads from a Scene; the Scene object itself (plugin classes made at run time) does
        # not pickle, and the packed tables are all the kernels see.
        return SimpleNamespace(integrator=SimpleNamespace(kernel=self.integrator), width=self.width,
                               height=self.height, sample_count=self.sample_count, sample_border=self.sample_border)


@dataclass(frozen=True)
class SharedScene:
    """Where the scene is on a filesystem that every worker sees."""
    key: str
    source: SceneSource


# ------------------------------------------------------------------------------------------ worker side
_CACHE: "OrderedDict[tuple, tuple]" = OrderedDict()   # (scene key, device spec) -> (Renderer, lock)
_CACHE_LOCK = threading.Lock()


def _worker_identity():
    try:
        from distributed import get_worker

        w = get_worker()
        return w.address, w.name
    except (ImportError, ValueError):
        return f"pid {os.getpid()}", None


def _device_spec(plan, worker_name):
    """The device this worker renders on: one spec for all, or one per LocalCluster worker by its name."""
    if plan is None or isinstance(plan, str):
        return plan
    try:
        return plan[int(worker_name) % len(plan)]
    except (TypeError, ValueError):
        return plan[0]


def _renderer_for(payload, spec, worker, driver="auto", reconstruction="auto"):
    from . import plugins  # noqa: F401  (a worker is a composition root: shipped tables need the plugins' code)
    from .renderer import Renderer

    key = (payload.key, spec, driver, reconstruction)
    with _CACHE_LOCK:
        if key in _CACHE:
            _CACHE.move_to_end(key)
            return _CACHE[key]
        try:
            if isinstance(payload, ShippedScene):
                renderer = Renderer(payload.scene(), device=spec, buffers=payload.buffers, driver=driver,
                                    reconstruction=reconstruction)
            else:
                got = payload.source.content_hash()
                if got != payload.key:
                    raise TaskFailed("scene", worker, spec or "default device",
                                     f"the scene files at {payload.source.path} differ from the client's "
                                     f"(hash {got} != {payload.key}); use the same files or files='ship'")
                renderer = Renderer(payload.source.load(), device=spec, driver=driver,
                                    reconstruction=reconstruction)
        except TaskFailed:
            raise
        except DeviceError as exc:
            raise TaskFailed("device", worker, f"device {spec or 'default'}", str(exc)) from None
        except ClrenderError as exc:
            raise TaskFailed("scene", worker, spec or "default device", str(exc)) from None
        except Exception as exc:  # an OpenCL driver error while building or uploading
            raise TaskFailed("device", worker, f"device {spec or 'default'}",
                             f"{type(exc).__name__}: {exc}") from None
        _CACHE[key] = (renderer, threading.Lock())
        while len(_CACHE) > WORKER_CACHE_SCENES:
            _CACHE.popitem(last=False)
        return _CACHE[key]


def render_task(payload, index, pixels, start, count, seed, plan, driver="auto", reconstruction="auto"):
    """One task on a worker: samples start..start+count-1 of pixels [pixels[0], pixels[1]), by `driver` with the
    film's `reconstruction` (clrender/executors.py)."""
    from .version import __version__

    worker, name = _worker_identity()
    spec = _device_spec(plan, name)
    renderer, lock = _renderer_for(payload, spec, worker, driver, reconstruction)
    p0, p1 = pixels
    t0 = time.perf_counter()
    with lock:  # one Renderer per device: tasks of a multi-threaded worker take turns
        try:
            acc = renderer.render_accumulators(spp=count, seed=seed, start_sample=start, pixels=(p0, p1))
        except Exception as exc:
            with _CACHE_LOCK:
                _CACHE.pop((payload.key, spec, driver, reconstruction), None)
            raise TaskFailed("device", worker, renderer.device_name, f"{type(exc).__name__}: {exc}") from None
    return {"index": index, "p0": p0, "start": start, "count": count, "accumulators": acc,
            "worker": worker, "device": renderer.device_name, "version": __version__,
            "seconds": time.perf_counter() - t0}

