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


def device_context():
    """The default OpenCL (context, queue), or None where there is none (the numpy build is used then)."""
    try:
        from ..device.context import get_context

        return get_context(None)
    except (DeviceError, ImportError, OSError) as exc:   # no driver, no device: not an error for a build
        import logging

        logging.getLogger(__name__).debug("BVH build on the host only: %s", exc)
        return None
    except Exception as exc:  # pyopencl raises its own errors (e.g. no platforms) from deep inside
        if type(exc).__module__.startswith("pyopencl"):
            return None
        raise


def build_subtrees(ctx_queue, L, H, ids, off, n, depth, max_leaf, ct, ci, force_depth):
    """Build the subtrees of ``len(off)`` tasks; task s owns rows [off[s], off[s] + n[s]) of the primitive
    rows L, H (three float32 coordinate arrays each: box lo / hi) and ids.

    Returns (ids in leaf order within each task's rows, per task node counts, lo (K, 3), hi (K, 3),
    meta (K, 4) int32 of all tasks' nodes concatenated task by task, local node 0 first: meta = (left child
    or -1, first primitive relative to the task, leaf count, depth below the task's root)).
    """
    import pyopencl as cl

    from ..device.program import build_program

    ctx, queue = ctx_queue
    prg = build_program(ctx, SOURCE, defines={"BVH_BINS": BINS}, with_types=False)
    M = len(ids)
    T = len(off)
    plo = np.empty((M, 4), np.float32)
    phi = np.empty((M, 4), np.float32)
    for a in range(3):
        plo[:, a] = L[a]
        phi[:, a] = H[a]
    plo[:, 3] = 0
    phi[:, 3] = 0
    pid = np.ascontiguousarray(ids, np.int32)
    # Larger tasks first: the device's scheduler then balances the tail with the small ones.
    by_size = np.argsort(-n, kind="stable")
    mf = cl.mem_flags
    rw = mf.READ_WRITE | mf.COPY_HOST_PTR
    ro = mf.READ_ONLY | mf.COPY_HOST_PTR
    b_lo = cl.Buffer(ctx, rw, hostbuf=plo)
    b_hi = cl.Buffer(ctx, rw, hostbuf=phi)
    b_id = cl.Buffer(ctx, rw, hostbuf=pid)
    b_off = cl.Buffer(ctx, ro, hostbuf=np.ascontiguousarray(off[by_size], np.int32))
    b_n = cl.Buffer(ctx, ro, hostbuf=np.ascontiguousarray(n[by_size], np.int32))
    b_d = cl.Buffer(ctx, ro, hostbuf=np.ascontiguousarray(depth[by_size], np.int32))
    slots = 2 * M
    b_nlo = cl.Buffer(ctx, mf.READ_WRITE, 16 * slots)
    b_nhi = cl.Buffer(ctx, mf.READ_WRITE, 16 * slots)
    b_meta = cl.Buffer(ctx, mf.READ_WRITE, 16 * slots)
    b_cnt = cl.Buffer(ctx, mf.READ_WRITE, 4 * T)
    k = cl.Kernel(prg, "bvh_build_subtrees")
    # One work-item per work-group: the subtrees diverge completely, and groups are what the cores share.
    k(queue, (T,), (1,), b_lo, b_hi, b_id, b_off, b_n, b_d, b_nlo, b_nhi, b_meta, b_cnt, np.uint32(T),
      np.int32(max_leaf), np.float32(ct), np.float32(ci), np.int32(force_depth))
    cnt_sorted = np.empty(T, np.int32)
    cl.enqueue_copy(queue, cnt_sorted, b_cnt)
    cl.enqueue_copy(queue, pid, b_id)
    nlo = np.empty((slots, 4), np.float32)
    nhi = np.empty((slots, 4), np.float32)
    meta = np.empty((slots, 4), np.int32)
    cl.enqueue_copy(queue, nlo, b_nlo)
    cl.enqueue_copy(queue, nhi, b_nhi)
    cl.enqueue_copy(queue, meta, b_meta)
    queue.finish()
    counts = np.empty(T, np.int64)
    counts[by_size] = cnt_sorted
    if (counts < 1).any():
        raise DeviceError("BVH subtree build ran out of stack (depth > 64)")
    # Node slots of task s: [2 off[s], 2 off[s] + counts[s]).
    first = np.repeat(2 * off - (np.cumsum(counts) - counts), counts) + np.arange(counts.sum())
    return pid.astype(np.int64), counts, nlo[first, :3], nhi[first, :3], meta[first]
