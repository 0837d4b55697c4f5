"""The lower levels of the binary SAH build in OpenCL: one work-item builds one subtree (kernels/bvh_build.cl).

``build_bvh`` builds the top of the tree with numpy, level by level, until its nodes hold at most
``subtree_size`` primitives; those nodes ("tasks") are handed here all at once. Each work-item runs the
sequential binned-SAH build of its subtree in compiled C, so the whole width of the frontier is built in
parallel on every core (PoCL) or compute unit, without a numpy pass per level.
"""
from __future__ import annotations

import numpy as np

from ..errors import DeviceError

BINS = 32
SOURCE = '#include "bvh_build.cl"\n'


def device_context(spec=None):
    """The (context, queue) of device ``spec`` (None: the default device), or None where there is none (the
    numpy build is used then)."""
    try:
        from ..device.context import get_context

        return get_context(spec)
    except (DeviceError, ImportError, OSError) as exc:   # no driver, no device: not an error for a build
        import logging

        logging.getLogger(__name__).debug("BVH build on the host only: %s", exc)
        return None
    except Exception as exc:  # pyopencl raises its own errors (e.g. no platforms) from deep inside
        if type(exc).__module__.startswith("pyopencl"):
            return None
        raise


def build_subtrees(ctx_queue, L, H, ids, off, n, depth, start, max_leaf, ct, ci, force_depth):
    """Build the subtrees of ``len(off)`` tasks; task s owns rows [off[s], off[s] + n[s]) of the primitive
    rows L, H (three float32 coordinate arrays each: box lo / hi) and ids, its root is at ``depth[s]`` and its
    primitives go to leaf-order positions start[s] ....

    Returns (ids in leaf order within each task's rows, per task interior node counts (0: the root is a
    leaf), per task depth of the deepest leaf below the root, the tasks' nodes in the layout of
    kernels/bvh.h, float32 (4 K, 4), task after task, with task-local interior references).
    """
    import pyopencl as cl

    from ..device.codegen import constants_c
    from ..device.program import build_program

    ctx, queue = ctx_queue
    # the shared constants only: the builder reads no plugin row, so it needs no registered plugin
    prg = build_program(ctx, constants_c() + "\n" + SOURCE, defines={"BVH_BINS": BINS}, with_types=False)
    M = len(ids)
    T = len(off)
    plo = np.zeros((M, 4), np.float32)
    phi = np.zeros((M, 4), np.float32)
    for a in range(3):
        plo[:, a] = L[a]
        phi[:, a] = H[a]
    pid = np.ascontiguousarray(ids, np.int32)
    # Larger tasks first: the device's scheduler then balances the tail with the small ones.
    by_size = np.argsort(-n, kind="stable")
    mf = cl.mem_flags
    rw = mf.READ_WRITE | mf.COPY_HOST_PTR
    ro = mf.READ_ONLY | mf.COPY_HOST_PTR
    b_lo = cl.Buffer(ctx, rw, hostbuf=plo)
    b_hi = cl.Buffer(ctx, rw, hostbuf=phi)
    b_id = cl.Buffer(ctx, rw, hostbuf=pid)
    task = [cl.Buffer(ctx, ro, hostbuf=np.ascontiguousarray(x[by_size], dt))
            for x, dt in ((off, np.int32), (n, np.int32), (depth, np.int32), (start, np.uint32))]
    rows = max(4 * M, 4)
    b_out = cl.Buffer(ctx, mf.READ_WRITE, 16 * rows)
    b_stats = cl.Buffer(ctx, mf.READ_WRITE, 8 * T)
    k = cl.Kernel(prg, "bvh_build_subtrees")
    # One work-item per work-group: the subtrees diverge completely, and groups are what the cores share.
    k(queue, (T,), (1,), b_lo, b_hi, b_id, *task, b_out, b_stats, np.uint32(T), np.int32(max_leaf),
      np.float32(ct), np.float32(ci), np.int32(force_depth))
    stats_sorted = np.empty((T, 2), np.int32)
    cl.enqueue_copy(queue, stats_sorted, b_stats)
    stats = np.empty((T, 2), np.int64)
    stats[by_size] = stats_sorted
    if (stats[:, 0] < 0).any():
        raise DeviceError("BVH subtree build ran out of stack (depth > 64)")
    cl.enqueue_copy(queue, pid, b_id)
    # Mapped, not copied (no copy at all on a CPU device): only the used rows are read, one slice per task.
    out, _ = cl.enqueue_map_buffer(queue, b_out, cl.map_flags.READ, 0, (rows // 4, 4, 4), np.float32,
                                   wait_for=None, is_blocking=True)
    K = stats[:, 0]
    block = np.empty((int(K.sum()), 4, 4), np.float32)
    at = np.cumsum(K) - K
    for s in np.nonzero(K)[0]:
        block[at[s]:at[s] + K[s]] = out[off[s]:off[s] + K[s]]
    out.base.release(queue)
    return pid.astype(np.int64), K, stats[:, 1], block.reshape(-1, 4)
