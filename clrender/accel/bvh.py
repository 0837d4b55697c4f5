"""Binary SAH BVH: a vectorised host build and its flattening into the node table of kernels/bvh.h.

Build
-----
The tree is built top-down one *level* at a time: all nodes of the current frontier are split together
with whole-array numpy operations, never with a Python loop over primitives or nodes. Primitives live in
one array kept in leaf order; every node owns a contiguous range of it, and splitting a node reorders its
range so the left child's primitives come first.

* Nodes of more than ``SWEEP_MAX`` primitives use binned SAH: ``n_bins`` bins over the node's centroid
  bounds on each axis, per-(node, axis, bin) counts (``bincount``) and boxes (1-D ``minimum.at`` /
  ``maximum.at``, which numpy >= 1.25 runs on a fast path), prefix/suffix scans along the bins, best
  (axis, plane) per node, and a stable in-range partition from a cumulative sum.
* Smaller nodes are padded to 4/8/16/32 slots and get an exact full sweep (sort on each axis, prefix and
  suffix boxes), which beats 16 bins there and costs little because the arrays are tiny.
* SAH cost model: traversal 1, intersection 1 (both adjustable). A node becomes a leaf when it holds at most
  ``max_leaf_size`` primitives and a leaf is no more expensive than its best split; a larger node is always
  split. If all centroids of a node coincide (a pile of identical primitives) it is split in the middle of
  its range, so leaves stay bounded and the build terminates. Past depth ``64 - ceil(log2 N) - 4`` splits
  are also made in the middle of the range, which bounds the depth below 64 (the kernel's stack size).

Flattened node layout (``BVH.nodes``, float32 (4*K, 4), read as ``float4`` on the device)
-----------------------------------------------------------------------------------------
Only interior nodes are stored; each holds the boxes of *both* its children (64 bytes, 4 float4), so a
traversal step tests two boxes. Node ``k`` is rows ``4k .. 4k+3``::

    row 4k+0 = [ A.lo.x, A.lo.y, A.lo.z, as_float(A.ref) ]
    row 4k+1 = [ A.hi.x, A.hi.y, A.hi.z, as_float(A.count) ]
    row 4k+2 = [ B.lo.x, B.lo.y, B.lo.z, as_float(B.ref) ]
    row 4k+3 = [ B.hi.x, B.hi.y, B.hi.z, as_float(B.count) ]

for children A (left) and B (right). ``ref``/``count`` are uint32 bit patterns:

* interior child: ``ref`` = its node index ``k'`` (bit 31 clear), ``count`` = 0;
* leaf child: ``ref`` = ``0x80000000 | first``, ``count`` = number of primitives; the leaf's primitives are
  rows ``first .. first+count-1`` of the primitive table in leaf order (``pack_primitives(..., order)``),
  i.e. float4 rows ``3*first ..``;
* empty slot: a leaf with count 0 (only when the whole scene is one leaf, or the scene is empty).

Node 0 is the root. Nodes are in depth-first order (the left child of node ``k``, if interior, is node
``k+1``). A scene whose root is a leaf (few primitives) still has one node: leaf in slot A, empty slot B. An
empty scene has one node with two empty slots.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

LEAF_FLAG = 0x80000000
SWEEP_MAX = 32
_SWEEP_PADS = (4, 8, 16, 32)
KERNEL_STACK_SIZE = 64


@dataclass
class BVH:
    """A flattened BVH (see the module docstring for the node layout)."""

    nodes: np.ndarray        # float32 (4*node_count, 4), integers bit-cast into .w
    order: np.ndarray        # int64 (N,): primitive ids in leaf order
    node_count: int          # flattened (2-wide) nodes
    depth: int               # levels of the binary tree, root = 1 (a single leaf has depth 1)
    build_seconds: float
    sah_cost: float          # SAH cost of the binary tree relative to the root box (traversal 1, intersection 1)
    leaf_count: int = 0
    max_leaf_prims: int = 0


def _half_area(lo, hi):
    d = np.maximum(hi - lo, 0.0)
    return d[..., 0] * d[..., 1] + d[..., 1] * d[..., 2] + d[..., 2] * d[..., 0]


def _scan(x, op, axis, reverse=False):
    """Inclusive prefix scan of ``op`` along a short ``axis``; a loop of whole-slice ops is ~15x faster than
    ``ufunc.accumulate`` along a non-last axis."""
    y = np.moveaxis(np.array(x, copy=True), axis, 0)
    rng = range(len(y) - 2, -1, -1) if reverse else range(1, len(y))
    step = 1 if reverse else -1
    for k in rng:
        op(y[k + step], y[k], out=y[k])
    return np.moveaxis(y, 0, axis)


def _segment_ids(counts):
    return np.repeat(np.arange(len(counts)), counts)


def _binned(A, off, n, cmin, cmax, n_bins):
    """Binned SAH for the (large) segments (off, n) of A: returns (best unnormalised cost, src order, n_left).

    A is (9, M+1) float32: rows lo xyz, 2*centroid xyz, hi xyz; column M is a sentinel. ``src`` lists, for the segments' slots in A, which
    element goes there (absolute indices into A).
    """
    B = len(off)
    seg = _segment_ids(n)
    elem = (np.repeat(off - np.concatenate([[0], np.cumsum(n)[:-1]]), n) + np.arange(n.sum()))
    ext = cmax - cmin
    with np.errstate(divide="ignore"):
        # (1 - 2^-20) keeps the largest centroid in the last bin despite rounding.
        ok = ext > 1e-30                                        # tinier extents would overflow the scale
        scale = np.where(ok, n_bins * (1.0 - 2.0 ** -20) / np.where(ok, ext, 1), 0).astype(np.float32)
    bins = np.empty((3, len(elem)), np.int64)
    for a in range(3):
        b = ((A[3 + a, elem] - cmin[seg, a]) * scale[seg, a]).astype(np.int64)
        np.clip(b, 0, n_bins - 1, out=b)
        bins[a] = b
    key = ((seg * 3)[None, :] + np.arange(3)[:, None]) * n_bins + bins    # (3, Mb)
    cells = B * 3 * n_bins
    cnt = np.bincount(key.ravel(), minlength=cells).reshape(B, 3, n_bins)
    bmin = np.empty((3, cells), np.float32)
    bmax = np.empty((3, cells), np.float32)
    for j in range(3):
        bmin[j].fill(np.inf)
        bmax[j].fill(-np.inf)
        vlo, vhi = np.take(A[j], elem), np.take(A[6 + j], elem)
        for a in range(3):
            np.minimum.at(bmin[j], key[a], vlo)
            np.maximum.at(bmax[j], key[a], vhi)
    bmin = bmin.T.reshape(B, 3, n_bins, 3)
    bmax = bmax.T.reshape(B, 3, n_bins, 3)
    lmin = _scan(bmin, np.minimum, 2)[:, :, :-1]
    lmax = _scan(bmax, np.maximum, 2)[:, :, :-1]
    rmin = _scan(bmin, np.minimum, 2, reverse=True)[:, :, 1:]
    rmax = _scan(bmax, np.maximum, 2, reverse=True)[:, :, 1:]
    nl = np.cumsum(cnt, axis=2)[:, :, :-1]
    nr = n[:, None, None] - nl
    with np.errstate(invalid="ignore"):
        cost = (_half_area(lmin.astype(np.float64), lmax.astype(np.float64)) * nl
                + _half_area(rmin.astype(np.float64), rmax.astype(np.float64)) * nr)
    cost = np.where((nl > 0) & (nr > 0), cost, np.inf).reshape(B, -1)
    best = np.argmin(cost, axis=1)
    best_cost = cost[np.arange(B), best]
    axis, plane = best // (n_bins - 1), best % (n_bins - 1)
    n_left = nl.reshape(B, -1)[np.arange(B), best]
    # Stable partition inside each segment: left elements keep their order, then right ones.
    left = bins[axis[seg], np.arange(len(elem))] <= plane[seg]
    cl = np.cumsum(left)
    first = np.concatenate([[0], np.cumsum(n)[:-1]])
    before = (cl - left)[first]                                 # lefts before each segment
    rank_l = cl - left - before[seg]
    pos = np.arange(len(elem)) - first[seg]
    dest = np.where(left, rank_l, n_left[seg] + pos - rank_l) + off[seg]
    src_slots = np.empty_like(elem)
    src_slots[dest - off[seg] + first[seg]] = elem
    return best_cost, src_slots, n_left


def _sweep(A, off, n, pad):
    """Exact sweep SAH for small segments padded to ``pad`` slots: (best cost, src order, n_left).

    A's last column must be a sentinel (empty box, centroid +inf): padding slots point at it, so gathers
    need no masking and padding sorts last.
    """
    S = len(off)
    sentinel = A.shape[1] - 1
    k = np.arange(pad)
    valid = k[:, None] < n[None, :]                             # (pad, S): slot-major so scans run over
    idx = np.where(valid, off[None, :] + k[:, None], sentinel)  # long contiguous rows
    nl = (k[:-1] + 1)[:, None].astype(np.float32)
    nr = n[None, :].astype(np.float32) - nl
    best_cost = np.full(S, np.inf, np.float32)
    best_i = np.zeros(S, np.int64)
    best_order = idx
    for a in range(3):
        # Ties may come out in any order: any split between equal centroids is as good as another.
        o = np.argsort(np.take(A[3 + a], idx.T), axis=1).T
        sidx = np.take_along_axis(idx, o, axis=0)
        blo, bhi = np.take(A[0:3], sidx, axis=1), np.take(A[6:9], sidx, axis=1)   # (3, pad, S)
        lmin = _scan(blo, np.minimum, 1)[:, :-1]
        lmax = _scan(bhi, np.maximum, 1)[:, :-1]
        rmin = _scan(blo, np.minimum, 1, reverse=True)[:, 1:]
        rmax = _scan(bhi, np.maximum, 1, reverse=True)[:, 1:]
        with np.errstate(invalid="ignore"):
            cost = _half_area3(lmin, lmax) * nl + _half_area3(rmin, rmax) * nr
        cost[~(nr > 0)] = np.inf
        i = np.argmin(cost, axis=0)
        c = cost[i, np.arange(S)]
        better = c < best_cost
        best_cost = np.where(better, c, best_cost)
        best_i = np.where(better, i, best_i)
        best_order = np.where(better[None, :], sidx, best_order)
    src = best_order.T[valid.T]                                 # segment by segment, slot order
    return best_cost.astype(np.float64), src, best_i + 1


def _half_area3(lo, hi):
    """Half surface area of boxes stored coordinate-first: lo, hi of shape (3, ...)."""
    d = np.maximum(hi - lo, np.float32(0))
    return d[0] * d[1] + d[1] * d[2] + d[2] * d[0]


def _empty_nodes():
    nodes = np.zeros((4, 4), np.float32)
    u = nodes.view(np.uint32)
    u[0, 3] = u[2, 3] = LEAF_FLAG
    return nodes


def build_bvh(lo, hi, max_leaf_size=4, n_bins=16, traversal_cost=1.0, intersection_cost=1.0):
    """Build a binned-SAH BVH over boxes ``lo``/``hi`` (N, 3) and flatten it (layout: module docstring)."""
    t0 = time.perf_counter()
    lo = np.ascontiguousarray(lo, np.float32).reshape(-1, 3)
    hi = np.ascontiguousarray(hi, np.float32).reshape(-1, 3)
    N = len(lo)
    max_leaf_size = max(1, int(max_leaf_size))
    n_bins = max(2, int(n_bins))
    if N == 0:
        return BVH(_empty_nodes(), np.zeros(0, np.int64), 1, 0, time.perf_counter() - t0, 0.0, 0, 0)

    # The active set: primitives of the frontier nodes only, each node a contiguous run, in frontier order.
    # Rows: lo xyz, 2*centroid xyz, hi xyz (so min-reductions read rows 0-5 and max-reductions rows 3-8).
    # The last column is a sentinel (empty box, centroid +inf) that _sweep pads with.
    A = np.empty((9, N + 1), np.float32)
    A[0:3, :N] = lo.T
    A[3:6, :N] = lo.T + hi.T
    A[6:9, :N] = hi.T
    A[0:6, N] = np.inf
    A[6:9, N] = -np.inf
    ids = np.arange(N, dtype=np.int64)
    order = np.empty(N, np.int64)
    force_depth = max(1, KERNEL_STACK_SIZE - math.ceil(math.log2(max(N, 2))) - 4)

    # Binary nodes, appended level by level (children always after their parent).
    root_lo, root_hi = lo.min(axis=0), hi.max(axis=0)
    b_lo, b_hi, b_start, b_count = [root_lo[None]], [root_hi[None]], [np.array([0])], [np.array([N])]
    lefts, level_first = [], [0]
    n_nodes = 1
    # Frontier: node ids, starts in the final order, counts, centroid bounds, box half-areas.
    f_id, f_start, f_n = np.array([0]), np.array([0]), np.array([N])
    f_cmin, f_cmax = A[3:6, :N].min(axis=1)[None], A[3:6, :N].max(axis=1)[None]
    f_area = _half_area(root_lo.astype(np.float64), root_hi.astype(np.float64))[None]
    depth = 0
    while len(f_id):
        depth += 1
        F = len(f_id)
        M = A.shape[1] - 1
        off = np.concatenate([[0], np.cumsum(f_n)[:-1]])
        seg = np.repeat(np.arange(F), f_n)
        split_cost = np.full(F, np.inf)
        n_left = f_n // 2
        src = np.arange(M)

        multi = f_n >= 2
        coincident = np.all(f_cmax <= f_cmin, axis=1)
        forced = multi & (coincident | (depth >= force_depth))
        small = multi & ~forced & (f_n <= SWEEP_MAX)
        big = multi & ~forced & ~small
        if big.any():
            sel = np.nonzero(big)[0]
            c, s, nl = _binned(A, off[sel], f_n[sel], f_cmin[sel], f_cmax[sel], n_bins)
            split_cost[sel], n_left[sel] = c, nl
            src[big[seg]] = s
        lo_pad = 1
        for pad in _SWEEP_PADS:
            m = small & (f_n > lo_pad) & (f_n <= pad)
            lo_pad = pad
            if m.any():
                sel = np.nonzero(m)[0]
                c, s, nl = _sweep(A, off[sel], f_n[sel], pad)
                split_cost[sel], n_left[sel] = c, nl
                src[m[seg]] = s
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(f_area > 0, split_cost / f_area, np.where(np.isfinite(split_cost), f_n, np.inf))
        sah_split = traversal_cost + intersection_cost * ratio
        # No usable plane (coincident centroids, depth limit): split mid-range so the node still shrinks.
        n_left = np.where(np.isfinite(split_cost), n_left, f_n // 2)
        leaf = (f_n <= max_leaf_size) & (intersection_cost * f_n <= sah_split)

        # Leaves retire from the active set; their primitives take their final places in the leaf order.
        leaf_el = leaf[seg]
        order[(f_start - off)[seg][leaf_el] + np.nonzero(leaf_el)[0]] = ids[leaf_el]
        sp = np.nonzero(~leaf)[0]
        if len(sp) == 0:
            break
        keep = src[~leaf_el]
        A = A[:, np.append(keep, M)]
        ids = ids[keep]

        # Children tile the new active set: left then right of each split node.
        c_n = np.stack([n_left[sp], f_n[sp] - n_left[sp]], axis=1).ravel()
        c_off = np.concatenate([[0], np.cumsum(c_n)[:-1]])
        red_min = np.minimum.reduceat(A[0:6, :-1], c_off, axis=1)
        red_max = np.maximum.reduceat(A[3:9, :-1], c_off, axis=1)
        c_lo, c_hi = red_min[0:3].T, red_max[3:6].T
        c_start = np.stack([f_start[sp], f_start[sp] + n_left[sp]], axis=1).ravel()
        c_id = n_nodes + np.arange(len(c_n))
        lefts.append((f_id[sp], c_id[0::2]))
        b_lo.append(c_lo); b_hi.append(c_hi); b_start.append(c_start); b_count.append(c_n)
        level_first.append(n_nodes)
        n_nodes += len(c_n)
        f_id, f_start, f_n = c_id, c_start, c_n
        f_cmin, f_cmax = red_min[3:6].T, red_max[0:3].T
        f_area = _half_area(c_lo.astype(np.float64), c_hi.astype(np.float64))
    level_first.append(n_nodes)

    blo = np.concatenate(b_lo).astype(np.float32)
    bhi = np.concatenate(b_hi).astype(np.float32)
    bstart = np.concatenate(b_start)
    bcount = np.concatenate(b_count)
    bleft = np.full(n_nodes, -1, np.int64)
    for (p, c) in lefts:
        bleft[p] = c
    bright = np.where(bleft >= 0, bleft + 1, -1)                # siblings are created side by side
    nodes, node_count = _flatten(blo, bhi, bstart, bcount, bleft, bright, level_first)

    inner = bleft >= 0
    area = _half_area(blo.astype(np.float64), bhi.astype(np.float64))
    root_area = area[0] if area[0] > 0 else 1.0
    sah = (traversal_cost * area[inner].sum() + intersection_cost * (area[~inner] * bcount[~inner]).sum()) / root_area
    return BVH(nodes=nodes, order=order, node_count=node_count, depth=len(level_first) - 1,
               build_seconds=time.perf_counter() - t0, sah_cost=float(sah),
               leaf_count=int((~inner).sum()), max_leaf_prims=int(bcount[~inner].max()))


def _flatten(blo, bhi, bstart, bcount, bleft, bright, level_first):
    """Binary tree (nodes in level order) -> depth-first 2-wide node table (module docstring)."""
    n = len(blo)
    inner = bleft >= 0
    if not inner[0]:                                            # the root is a leaf: leaf in A, empty slot in B
        nodes = _empty_nodes()
        u = nodes.view(np.uint32)
        nodes[0, :3], nodes[1, :3] = blo[0], bhi[0]
        u[0, 3] = LEAF_FLAG | np.uint32(bstart[0])
        u[1, 3] = bcount[0]
        nodes[2, :3], nodes[3, :3] = blo[0], bhi[0]
        return nodes, 1
    size = inner.astype(np.int64)                                # interior nodes in each subtree
    for d in range(len(level_first) - 2, -1, -1):
        lv = np.arange(level_first[d], level_first[d + 1])
        lv = lv[inner[lv]]
        size[lv] += size[bleft[lv]] + size[bright[lv]]
    flat = np.full(n, -1, np.int64)
    flat[0] = 0
    for d in range(len(level_first) - 1):
        lv = np.arange(level_first[d], level_first[d + 1])
        lv = lv[inner[lv]]
        flat[bleft[lv]] = flat[lv] + 1
        flat[bright[lv]] = flat[lv] + 1 + size[bleft[lv]]
    ids = np.nonzero(inner)[0]
    K = len(ids)
    nodes = np.zeros((K, 4, 4), np.float32)
    u = nodes.view(np.uint32)
    rows = flat[ids]
    for slot, child in ((0, bleft[ids]), (2, bright[ids])):
        nodes[rows, slot, :3] = blo[child]
        nodes[rows, slot + 1, :3] = bhi[child]
        leafc = bleft[child] < 0
        ref = np.where(leafc, bstart[child] | LEAF_FLAG, flat[child])
        u[rows, slot, 3] = ref.astype(np.uint32)
        u[rows, slot + 1, 3] = np.where(leafc, bcount[child], 0).astype(np.uint32)
    return nodes.reshape(4 * K, 4), K


def build_scene_bvh(tri_v0, tri_v1, tri_v2, spheres, **kw):
    """Convenience: bounds, build and packed primitives in one call -> (BVH, prims float32 (3N, 4))."""
    from .primitives import pack_primitives, primitive_bounds

    lo, hi = primitive_bounds(tri_v0, tri_v1, tri_v2, spheres)
    bvh = build_bvh(lo, hi, **kw)
    return bvh, pack_primitives(tri_v0, tri_v1, tri_v2, spheres, bvh.order)
