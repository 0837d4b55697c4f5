"""4-wide BVH: the binary tree of :mod:`clrender.accel.bvh` collapsed into the node table of kernels/bvh4.h.

Collapse
--------
Reads only the flattened 2-wide node table (``BVH.nodes``), so it works with whatever tree the builder
makes. Every 4-wide node starts from one binary node's two children and then, twice, replaces its interior
child of largest surface area by that child's own two children (the usual greedy SAH-driven collapse), so a
4-wide node has 2 to 4 children. Nodes are numbered level by level (breadth first), the children of one node
side by side. The work is whole-array numpy per level; no Python loop over nodes.

Node layout (8 ``float4`` = 128 bytes, two cache lines; node k is nodes[8k .. 8k+7])::

    [8k+0] lo.x of children 0..3      [8k+1] hi.x of children 0..3
    [8k+2] lo.y                       [8k+3] hi.y
    [8k+4] lo.z                       [8k+5] hi.z
    [8k+6] as_float(ref) of children 0..3
    [8k+7] unused (0)

The traversal picks the near and far planes per axis from the ray's direction signs (row ``2a + (d<0)`` is
the near plane of axis a), so an *empty* child slot is an inverted box (lo = +1e30, hi = -1e30) that no ray
can enter. A child reference is either an interior node index (bit 31 clear) or a leaf::

    LEAF_FLAG | (count - 1) << 27 | first        (1 <= count <= 16, first + count <= 2**27)

whose primitives are rows first .. first+count-1 of the primitive table (unchanged from the 2-wide tree).
Node 0 is the root and is always an interior node (an empty scene's root has four empty slots).

``stack_need`` is the largest number of stack entries the kernel can hold at once (it pushes every hit child
of a node and then pops the nearest); :func:`collapse_bvh4` raises :class:`Bvh4Unsupported` when a tree
needs more than ``KERNEL_STACK_SIZE`` or a leaf does not fit the reference encoding, and the caller keeps the
2-wide tree.
"""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..device.layout import ENUMS

from .bvh import LEAF_FLAG, BVH

NODE_ROWS = 8                 # float4 rows per 4-wide node
KERNEL_STACK_SIZE = ENUMS["BVH4_STACK_SIZE"]   # one source with kernels/bvh4.h (clrender/device/layout.py)
COUNT_SHIFT = ENUMS["BVH4_COUNT_SHIFT"]
MAX_LEAF_COUNT = ENUMS["BVH4_MAX_LEAF_COUNT"]
MAX_FIRST = 1 << COUNT_SHIFT
EMPTY_LO = np.float32(1e30)
EMPTY_HI = np.float32(-1e30)


class Bvh4Unsupported(ValueError):
    """The binary tree cannot be expressed as a 4-wide table the kernel can traverse safely."""


@dataclass
class BVH4:
    nodes: np.ndarray        # float32 (8*node_count, 4), references bit-cast into row 6
    node_count: int
    depth: int               # levels of 4-wide nodes (root = 1)
    stack_need: int          # most stack entries the kernel holds at once
    collapse_seconds: float
    leaf_count: int = 0


def encode_leaf(first, count):
    first = np.asarray(first, np.int64)
    count = np.asarray(count, np.int64)
    return (np.uint32(LEAF_FLAG) | ((count - 1) << COUNT_SHIFT).astype(np.uint32) | first.astype(np.uint32))


def decode_leaf(ref):
    """(first, count) of leaf references (uint32 with LEAF_FLAG set)."""
    ref = np.asarray(ref, np.uint32)
    return (ref & np.uint32(MAX_FIRST - 1)).astype(np.int64), ((ref >> COUNT_SHIFT) & 15).astype(np.int64) + 1


def _half_area(lo, hi):
    d = np.maximum(hi - lo, 0.0)
    return d[..., 0] * d[..., 1] + d[..., 1] * d[..., 2] + d[..., 2] * d[..., 0]


def collapse_bvh4(bvh: BVH, stack_size: int = KERNEL_STACK_SIZE, width: int = 4) -> BVH4:
    """The 4-wide table described above; ``width=8`` gives the 8-wide table of kernels/bvh8.h instead (the
    same collapse opening six children instead of two; node k is rows 14k .. 14k+13: lo.x, hi.x, lo.y, hi.y,
    lo.z, hi.z and the references of children 0..7, eight floats each, 224 bytes)."""
    if width not in (4, 8):
        raise ValueError(f"width must be 4 or 8, got {width}")
    t0 = time.perf_counter()
    n2 = bvh.nodes.reshape(-1, 4, 4)
    u2 = n2.view(np.uint32)
    # The binary tree's child slots, slot 2k + s = child s of binary node k: boxes, references, counts.
    s_lo = np.ascontiguousarray(n2[:, [0, 2], :3]).reshape(-1, 3)
    s_hi = np.ascontiguousarray(n2[:, [1, 3], :3]).reshape(-1, 3)
    s_ref = u2[:, [0, 2], 3].reshape(-1)
    s_cnt = u2[:, [1, 3], 3].reshape(-1).astype(np.int64)
    s_leaf = (s_ref & np.uint32(LEAF_FLAG)) != 0
    s_valid = ~s_leaf | (s_cnt > 0)                             # count-0 leaves are empty slots
    s_inner = s_valid & ~s_leaf
    s_area = np.where(s_inner, _half_area(s_lo, s_hi), -1.0).astype(np.float32)   # only interiors open

    lf = s_leaf & s_valid
    if lf.any():
        first = (s_ref[lf] & np.uint32(~np.uint32(LEAF_FLAG))).astype(np.int64)
        cnt = s_cnt[lf]
        if cnt.max() > MAX_LEAF_COUNT or (first + cnt).max() > MAX_FIRST:
            raise Bvh4Unsupported(f"a leaf of {cnt.max()} primitives or {(first + cnt).max()} primitives in all "
                                  f"does not fit the 4-wide reference encoding")

    levels = []                                                 # per level: (B, 4) slot ids (-1 = empty)
    batch = np.array([0], np.int64)                             # binary nodes that become 4-wide nodes
    acc = np.array([0], np.int64)                               # stack entries pending above each node
    stack_need = 0
    while len(batch):
        B = len(batch)
        rows = np.arange(B)
        slot = np.full((B, width), -1, np.int64)
        slot[:, 0], slot[:, 1] = 2 * batch, 2 * batch + 1
        used = np.full(B, 2)
        for _ in range(width - 2):
            area = np.where(slot >= 0, s_area[slot], np.float32(-1.0))
            j = np.argmax(area, axis=1)
            ok = area[rows, j] >= 0                             # an interior child to open
            if not ok.any():
                break
            r, jj = rows[ok], j[ok]
            k = s_ref[slot[r, jj]].astype(np.int64)             # binary node being opened
            slot[r, jj] = 2 * k                                 # its first child replaces it,
            slot[r, used[ok]] = 2 * k + 1                       # its second takes the next free slot
            used[ok] += 1
        valid = slot >= 0
        valid[valid] = s_valid[slot[valid]]
        # Compact the valid children to the front (stable).
        order = np.argsort(~valid, axis=1, kind="stable")
        slot = np.take_along_axis(np.where(valid, slot, -1), order, 1)
        valid = slot >= 0
        inner = np.zeros_like(valid)
        inner[valid] = s_inner[slot[valid]]
        n_children = valid.sum(axis=1)
        stack_need = max(stack_need, int((acc + n_children).max()))
        levels.append((slot, inner))
        acc = np.repeat(acc + n_children - 1, inner.sum(axis=1))
        batch = s_ref[slot[inner]].astype(np.int64)             # row-major: children of a node side by side

    if stack_need > stack_size:
        raise Bvh4Unsupported(f"the 4-wide tree needs a stack of {stack_need} > {stack_size}")
    slot = np.concatenate([lv[0] for lv in levels])
    inner = np.concatenate([lv[1] for lv in levels])
    K = len(slot)
    valid = slot >= 0
    sv = slot[valid]
    ref = np.zeros((K, width), np.uint32)
    leaf = np.zeros_like(valid)
    leaf[valid] = ~s_inner[sv]
    first = (s_ref[slot[leaf]] & np.uint32(~np.uint32(LEAF_FLAG))).astype(np.int64)
    ref[leaf] = encode_leaf(first, s_cnt[slot[leaf]])
    # Interior children, row-major over the levels in order, are nodes 1, 2, ... (what n_total counted).
    ref[inner] = np.arange(1, 1 + int(inner.sum()), dtype=np.uint32)
    lo = np.full((K, width, 3), EMPTY_LO, np.float32)
    hi = np.full((K, width, 3), EMPTY_HI, np.float32)
    lo[valid], hi[valid] = s_lo[sv], s_hi[sv]
    nodes = np.zeros((K, NODE_ROWS if width == 4 else 7, width), np.float32)
    for a in range(3):
        nodes[:, 2 * a] = lo[:, :, a]
        nodes[:, 2 * a + 1] = hi[:, :, a]
    nodes[:, 6] = ref.view(np.float32)
    leaf_count = int(leaf.sum())
    return BVH4(nodes=nodes.reshape(-1, 4), node_count=K, depth=len(levels), stack_need=stack_need,
                collapse_seconds=time.perf_counter() - t0, leaf_count=leaf_count)
