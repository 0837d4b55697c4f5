"""Running media's tracking on the device, in bulk, for statistical tests (kernels/testing/media_batch.cl):
ratio tracking's transmittance estimates and delta tracking's real-collision distances along one ray through a
medium of a packed scene."""
from __future__ import annotations

import numpy as np

from .kernels import LOCAL, padded

MEDIA_SRC = '#include "testing/media_batch.cl"\n'   # kernels/testing/media_batch.cl


def medium_track_batch(ctx, queue, scene, o, d, t1: float, n: int, mode: str = "ratio", channel: int = 0,
                       medium: int = 0, seed: int = 7) -> np.ndarray:
    """`n` independent runs along o + t d, t in [0, t1], in row `medium` of the scene's packed media:
    mode "ratio": (n, 3) transmittance estimates; "delta": (n,) distances of the first real collision for
    `channel` (inf where there is none before t1)."""
    import pyopencl as cl

    from ..device.kernelargs import KernelArgs
    from ..device.program import build_program
    from ..pack import pack_scene
    from ..renderer import render_defines

    buffers = pack_scene(scene)
    prg = build_program(ctx, MEDIA_SRC, defines=render_defines(None, buffers))
    k = cl.Kernel(prg, "medium_track_batch")
    mf = cl.mem_flags
    # (pyopencl's set_arg keeps no reference: the buffers must stay alive while the kernel runs)
    bufs = {t: cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(x))
            for t, x in buffers.tables.items()}
    d_out = cl.Buffer(ctx, mf.WRITE_ONLY, n * 16)
    KernelArgs(k).set_scene(bufs).set(
        medium=np.uint32(medium), o=np.array([*o, 0], np.float32), d=np.array([*d, 0], np.float32),
        t1=np.float32(t1), channel=np.uint32(channel), mode=np.uint32({"ratio": 0, "delta": 1}[mode]),
        n=np.uint32(n), first=np.uint32(0), seed=np.uint32(seed), out=d_out)
    cl.enqueue_nd_range_kernel(queue, k, (padded(n),), (LOCAL,))
    out = np.empty((n, 4), np.float32)
    cl.enqueue_copy(queue, out, d_out)
    queue.finish()
    return out[:, :3].astype(np.float64) if mode == "ratio" else out[:, 0].astype(np.float64)
