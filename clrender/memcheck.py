"""Will a render fit? The film's accumulators are checked against the device's and the host's memory
before anything is allocated, so a 65536 x 65536 film is an error naming width/height, not a MemoryError."""
from __future__ import annotations

import os

import numpy as np

from .device import layout
from .errors import SceneError

#: bytes per pixel on the host beside the downloaded accumulators: the Film's float64 sums and its image
HOST_EXTRA_BYTES_PER_PIXEL = 2 * 32 + 8 + 8 + 8 + 12 + 24
#: pixels and sample numbers are 32-bit kernel arguments
MAX_PIXELS = 2**32 - 1


def available_host_memory() -> int | None:
    """Bytes the host can still give us (MemAvailable), None if unknown."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def _gib(n: float) -> str:
    return f"{n / 2**30:.1f} GiB"


def check_film_fits(scene, device, count_rays: bool = False, fixed_device_bytes: int = 0,
                    splat: bool = True) -> None:
    """Raise a SceneError at the camera's width/height if the film cannot be allocated (`splat`: with a splatting
    film's accumulators, which a film whose reconstruction is not decided yet may need)."""
    import pyopencl as cl

    w, h = int(scene.width), int(scene.height)
    n = w * h
    where = None
    cam = getattr(scene, "camera", None)
    spec = getattr(cam, "spec", None)
    if spec is not None:
        props = spec.props
        big = "width" if w >= h else "height"
        where = props.location(big) if big in props else spec.location
    film = f"the {w} x {h} film ({n / 1e6:.0f} M pixels)"
    hint = "; reduce width and/or height"
    if n > MAX_PIXELS:
        raise SceneError(f"{film} has more than {MAX_PIXELS} pixels, the most a render can address{hint}",
                         where)
    per_pixel = layout.film_bytes_per_pixel(count_rays, splat)
    # the largest accumulator buffer (acc0, acc1: one float4 per pixel)
    largest = n * max(np.dtype(dt).itemsize * int(np.prod(shape)) for dt, shape in
                      (layout.film_element(name) for name, _full in layout.film_buffers(count_rays, splat)))
    if largest > device.max_mem_alloc_size:
        raise SceneError(f"{film} needs {_gib(largest)} in one device buffer, but the device allows "
                         f"{_gib(device.max_mem_alloc_size)} per buffer{hint}", where)
    dev_bytes = per_pixel * n + fixed_device_bytes
    if dev_bytes > device.global_mem_size:
        raise SceneError(f"{film} needs {_gib(dev_bytes)} of device memory, but the device has "
                         f"{_gib(device.global_mem_size)}{hint}", where)
    host_bytes = (per_pixel + HOST_EXTRA_BYTES_PER_PIXEL) * n
    if device.type & cl.device_type.CPU:  # a CPU device's buffers live in host memory too
        host_bytes += dev_bytes
    avail = available_host_memory()
    if avail is not None and host_bytes > avail:
        raise SceneError(f"{film} needs about {_gib(host_bytes)} of host memory, but only {_gib(avail)} "
                         f"is available{hint}", where)
