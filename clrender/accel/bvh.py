"""Binary SAH BVH: a vectorised host build and its flattening into the node table of kernels/bvh.h.

Build
-----
The tree is built top-down one *level* at a time: all nodes of the current frontier are split together
with whole-array numpy operations, never with a Python loop over primitives or nodes. Primitives live in
one array kept in leaf order; every node owns a contiguous range of it, and splitting a node reorders its
range so the left child's primitives come first.

* Nodes of more than ``DP_MAX`` (4) primitives use binned SAH on all three axes: per-(node, axis, bin)
  counts (``bincount``) and boxes (1-D ``minimum.at`` / ``maximum.at``, which numpy >= 1.25 runs on a fast
  path) in cells laid out bin-major per bin count, prefix/suffix scans along the bins, best (axis, plane)
  per node, and a stable in-range partition from a cumulative sum. Bins per node: ``n_bins`` (16), 8 for
  nodes of <= 16 primitives (fewer cells where the frontier is widest). The children's boxes come from the
  bins (exact); their centroid bounds from a ``reduceat`` over the reordered primitives.
* Nodes of more than ``2 * sah_samples`` primitives bin an evenly strided sample of ``sah_samples`` of
  them (the split is still applied to all, and their children's boxes are reduced exactly). On the 1 M
  triangle blob this changes the SAH cost by < 0.1 % and removes most of the cost of the top levels.
* Nodes of 2..``DP_MAX`` primitives get their whole subtree at once from a dynamic programme over all
  subsets of their primitives (every two-way partition, not only planes): the exact SAH optimum of that
  subtree, including the leaf-or-split decision, for the price of ~30 small array operations.
* SAH cost model: traversal 1, intersection 1 (both adjustable). A node becomes a leaf when it holds at most
  ``max_leaf_size`` primitives and a leaf is no more expensive than its best split; a larger node is always
  split. If all centroids of a node coincide (a pile of identical primitives) it is split in the middle of
  its range, so leaves stay bounded and the build terminates. Past depth ``64 - ceil(log2 N) - 4`` splits
  are also made in the middle of the range, which bounds the depth below 64 (the kernel's stack size).
* Nodes are recorded with their depth; the flattening groups them by depth, so subtrees emitted early (the
  small-node programme) need no particular creation order beyond siblings being created side by side.
* ``method="device"`` (and "auto" for N >= ``DEVICE_MIN`` when there is an OpenCL device) stops the levels at
  nodes of <= N / (4 x compute units) primitives and hands those nodes over to kernels/bvh_build.cl
  (clrender/accel/bvh_device.py): one work-item builds one subtree sequentially in compiled C, binning
  *every* primitive in 32 bins (so its SAH is at least as good as the sampled 16-bin host levels) with the
  same leaf rule and the same exact programme for <= 4 primitives, and writes it already flattened; the host
  then places each subtree's block of nodes and moves its references. A pass over all N primitives per
  level, which is what the host build pays at every level, is paid only for the few top levels.

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

from ..device.layout import ENUMS

LEAF_FLAG = ENUMS["BVH_LEAF_BIT"]
SAH_SAMPLES = 1024
DEVICE_MIN = 65536          # "auto" builds smaller scenes on the host (fast enough; no kernel compile)
DEVICE_TASKS_PER_UNIT = 4  # the host's levels stop at nodes of <= N / (4 x compute units) primitives ...
DEVICE_SUBTREE_MIN = 4096   # ... or <= this many
DP_MAX = 4
KERNEL_STACK_SIZE = ENUMS["BVH_STACK_SIZE"]


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


def _empty_nodes():
    nodes = np.zeros((4, 4), np.float32)
    u = nodes.view(np.uint32)
    u[0, 3] = u[2, 3] = LEAF_FLAG
    return nodes


# -------------------------------------------------------------------------------------------- build
_BIN_CLASSES = ((16, 8),)                  # (largest node, bins): nodes of <= 16 primitives get 8 bins, ...


def _node_bins(n, n_bins, sample_above):
    """Bins per node by its size."""
    nb = np.full(len(n), n_bins, np.int64)
    for top, b in reversed(_BIN_CLASSES):
        nb[n <= top] = min(b, n_bins)
    nb[n > sample_above] = max(n_bins, 2)
    return nb


def _spreader(counts):
    """x -> np.repeat(x, counts), by a gather when the nodes are small (faster there)."""
    F, M = len(counts), int(counts.sum())
    if F * 16 < M:
        return lambda x: np.repeat(x, counts)
    seg = np.repeat(np.arange(F), counts)
    return lambda x: np.take(x, seg)


def _select(k, x):
    """x[k[i]][i] for a list x of three equally long arrays (k in 0..2)."""
    return np.where(k == 0, x[0], np.where(k == 1, x[1], x[2]))


def _binned_splits(L, H, C, pos, per_node, nb, cmin, scale):
    """Binned SAH over the nodes of the frontier.

    L, H, C: the three lo / hi / doubled-centroid coordinate rows of the active primitives; pos: the positions
    of the primitives to bin (None = all), node by node, per_node: how many each node has; nb: bins per node (< 2 = skip); axes:
    (F, 3) the axes each node tries (-1 = none) in three *slots*; cmin/scale: per node and axis, bin =
    (centroid - cmin) * scale. Returns per node (inf / -1 where no plane was found): cost, axis, plane, and
    the left / right boxes of the best split from the bins (exact when every primitive of the node was binned).
    """
    F = len(nb)
    cost = np.full(F, np.inf)
    axis = np.zeros(F, np.int64)
    plane = np.full(F, -1, np.int64)
    box = np.zeros((4, F, 3), np.float32)              # left lo, left hi, right lo, right hi
    # Cells: the nodes of one bin count form a block [base, base + nb * F_c), bin-major (cell = base +
    # bin * F_c + node) so the scans below run over contiguous rows. Every axis has its own cells.
    cell0 = np.zeros(F, np.int64)
    stride = np.zeros(F, np.int64)
    blocks = []
    total = 0
    for b in np.unique(nb):
        if b < 2:
            continue
        ids = np.nonzero(nb == b)[0]
        cell0[ids] = total + np.arange(len(ids))
        stride[ids] = len(ids)
        blocks.append((b, ids, total))
        total += len(ids) * b
    dump = total                                       # one cell for primitives of skipped nodes
    total += 1
    skip = nb < 2
    rep = _spreader(per_node)                           # per node -> per primitive
    e_top = rep(np.maximum(nb - 1, 0))
    gather = (lambda x: x) if pos is None else (lambda x: x[pos])
    Lv, Hv, Cv = [gather(x) for x in L], [gather(x) for x in H], [gather(x) for x in C]
    base = rep(np.where(skip, dump, cell0))
    st = rep(np.where(skip, 0, stride))
    bins = []
    cnt = np.empty((3, total), np.float32)
    bmin = np.full((3, 3, total), np.inf, np.float32)
    bmax = np.full((3, 3, total), -np.inf, np.float32)
    for k in range(3):
        c, cm, sc = Cv[k], cmin[:, k], scale[:, k]
        bi = ((c - rep(cm)) * rep(sc)).astype(np.int64)
        np.clip(bi, 0, e_top, out=bi)
        if pos is None:
            bins.append(bi)
        key = base + bi * st
        cnt[k] = np.bincount(key, minlength=total)
        for j in range(3):
            np.minimum.at(bmin[k, j], key, Lv[j])
            np.maximum.at(bmax[k, j], key, Hv[j])
    for b, ids, base in blocks:
        Fc = len(ids)
        sl = slice(base, base + Fc * b)
        ymin = bmin[:, :, sl].reshape(3, 3, b, Fc)
        ymax = bmax[:, :, sl].reshape(3, 3, b, Fc)
        lmin, lmax = ymin.copy(), ymax.copy()
        for k in range(1, b):
            np.minimum(lmin[:, :, k - 1], lmin[:, :, k], out=lmin[:, :, k])
            np.maximum(lmax[:, :, k - 1], lmax[:, :, k], out=lmax[:, :, k])
        rmin, rmax = ymin, ymax                         # in place: the bins are not needed afterwards
        for k in range(b - 2, -1, -1):
            np.minimum(rmin[:, :, k + 1], rmin[:, :, k], out=rmin[:, :, k])
            np.maximum(rmax[:, :, k + 1], rmax[:, :, k], out=rmax[:, :, k])
        nl = cnt[:, sl].reshape(3, b, Fc)             # prefix counts (in place: the counts are not needed afterwards)
        for k in range(1, b):
            np.add(nl[:, k - 1], nl[:, k], out=nl[:, k])
        nr = nl[:, -1:] - nl[:, :-1]
        nl = nl[:, :-1]
        dl = lmax[:, :, :-1] - lmin[:, :, :-1]          # (3 axes, 3 coords, b-1, Fc)
        dr = rmax[:, :, 1:] - rmin[:, :, 1:]
        np.maximum(dl, 0, out=dl)
        np.maximum(dr, 0, out=dr)
        cst = (dl[:, 0] * dl[:, 1] + dl[:, 1] * dl[:, 2] + dl[:, 2] * dl[:, 0]) * nl
        cst += (dr[:, 0] * dr[:, 1] + dr[:, 1] * dr[:, 2] + dr[:, 2] * dr[:, 0]) * nr
        cst[(nl == 0) | (nr == 0)] = np.inf
        cst = cst.reshape(3 * (b - 1), Fc)               # candidates: axis-major, then plane
        best = np.argmin(cst, axis=0)
        r = np.arange(Fc)
        cost[ids] = cst[best, r]
        ax, pl = best // (b - 1), best % (b - 1)
        axis[ids], plane[ids] = ax, pl
        for j in range(3):
            box[0, ids, j] = lmin[ax, j, pl, r]
            box[1, ids, j] = lmax[ax, j, pl, r]
            box[2, ids, j] = rmin[ax, j, pl + 1, r]
            box[3, ids, j] = rmax[ax, j, pl + 1, r]
    bad = ~np.isfinite(cost)
    plane[bad] = -1
    axis[bad] = 0
    return cost, axis, plane, box, (bins if pos is None else None)


def _range_reduce(x, starts, ends, op):
    """op.reduce over each non-empty range [starts[i], ends[i]) of x."""
    if len(starts) == 0:
        return np.empty(0, x.dtype)
    idx = np.stack([starts, ends], axis=1).ravel()
    if idx[-1] >= len(x):
        idx = idx[:-1]
    return op.reduceat(x, idx)[0::2]


class _Nodes:
    """Binary nodes in creation order; siblings are always created side by side (right = left + 1)."""

    def __init__(self):
        self.lo, self.hi, self.start, self.count, self.depth, self.links = [], [], [], [], [], []
        self.n = 0

    def add(self, lo, hi, start, count, depth):
        ids = self.n + np.arange(len(count))
        self.lo.append(np.asarray(lo, np.float32).reshape(-1, 3))
        self.hi.append(np.asarray(hi, np.float32).reshape(-1, 3))
        self.start.append(np.asarray(start, np.int64))
        self.count.append(np.asarray(count, np.int64))
        self.depth.append(np.broadcast_to(np.asarray(depth, np.int64), len(count)))
        self.n += len(count)
        return ids

    def add_children(self, parents, l_lo, l_hi, r_lo, r_hi, l_start, l_n, r_n, depth):
        """Children of ``parents``: left and right interleaved; returns the left ids."""
        ids = self.add(np.stack([l_lo, r_lo], 1), np.stack([l_hi, r_hi], 1),
                       np.stack([l_start, l_start + l_n], 1).ravel(), np.stack([l_n, r_n], 1).ravel(),
                       np.repeat(np.broadcast_to(np.asarray(depth, np.int64), len(parents)), 2))
        self.links.append((np.asarray(parents, np.int64), ids[0::2]))
        return ids[0::2]


_POPCOUNT = np.array([bin(m).count("1") for m in range(1 << DP_MAX)], np.int64)


def _small_subtrees(nodes, Lg, Hg, ids_g, node_id, start, depth, order, max_leaf, ct, ci):
    """Optimal SAH subtrees for S nodes of exactly n <= DP_MAX primitives each, by dynamic programming over
    all subsets of each node's primitives (every two-way partition, not only planes).

    Lg, Hg: (3, n, S) boxes of the primitives in slot order; ids_g (n, S) their ids. Emits the subtrees' nodes
    below ``node_id`` and writes the leaves' primitives into ``order`` (slot order within a leaf).
    """
    n, S = Lg.shape[1], Lg.shape[2]
    full = (1 << n) - 1
    blo = np.empty((full + 1, 3, S), np.float32)
    bhi = np.empty((full + 1, 3, S), np.float32)
    cost = np.empty((full + 1, S))
    choice = np.zeros((full + 1, S), np.int64)                  # 0 = leaf, else the left part (has the low bit)
    for m in range(1, full + 1):
        low = m & -m
        if m == low:
            i = low.bit_length() - 1
            blo[m], bhi[m] = Lg[:, i], Hg[:, i]
        else:
            np.minimum(blo[low], blo[m ^ low], out=blo[m])
            np.maximum(bhi[low], bhi[m ^ low], out=bhi[m])
        d = np.maximum(bhi[m] - blo[m], np.float32(0)).astype(np.float64)
        area = d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
        k = int(_POPCOUNT[m])
        best = ci * k * area if k <= max_leaf else np.full(S, np.inf)
        ch = choice[m]
        rest = m ^ low
        t = (rest - 1) & rest                                   # proper subsets of rest, largest first
        while rest:
            sub = low | t
            c = ct * area + cost[sub] + cost[m ^ sub]
            better = c < best
            best = np.where(better, c, best)
            ch[better] = sub
            if t == 0:
                break
            t = (t - 1) & rest
        cost[m] = best
    # Emit top-down: (group column, mask, node id, start, depth) per open node.
    col = np.arange(S)
    mask = np.full(S, full)
    while len(col):
        ch = choice[mask, col]
        lf = ch == 0
        if lf.any():
            lc, lm, ls = col[lf], mask[lf], start[lf]
            for i in range(n):
                has = (lm >> i) & 1 == 1
                rank = _POPCOUNT[lm[has] & ((1 << i) - 1)]
                order[ls[has] + rank] = ids_g[i, lc[has]]
        sp = ~lf
        if not sp.any():
            break
        col, mask, ch, node_id, start, depth = col[sp], mask[sp], ch[sp], node_id[sp], start[sp], depth[sp]
        rm = mask ^ ch
        lid = nodes.add_children(node_id, blo[ch, :, col], bhi[ch, :, col], blo[rm, :, col], bhi[rm, :, col],
                                 start, _POPCOUNT[ch], _POPCOUNT[rm], depth + 1)
        col = np.repeat(col, 2)
        mask = np.stack([ch, rm], 1).ravel()
        node_id = np.stack([lid, lid + 1], 1).ravel()
        start = np.stack([start, start + _POPCOUNT[ch]], 1).ravel()
        depth = np.repeat(depth + 1, 2)


def build_bvh(lo, hi, max_leaf_size=4, n_bins=16, traversal_cost=1.0, intersection_cost=1.0,
              sah_samples=SAH_SAMPLES, method="auto", subtree_size=None, device=None):
    """Build a binned-SAH BVH over boxes ``lo``/``hi`` (N, 3) and flatten it (layout: module docstring).

    ``method``: "host" builds every level with numpy; "device" hands nodes of at most ``subtree_size``
    primitives (default: N / (4 x the device's compute units), at least 4096) to an OpenCL kernel that builds their subtrees, one per
    work-item (clrender/accel/bvh_device.py); "auto" does that for N >= DEVICE_MIN when an OpenCL device is
    there, else builds on the host. ``device``: an OpenCL device spec (clrender.device.context; default: the
    default device)."""
    if method not in ("auto", "host", "device"):
        raise ValueError(f"build_bvh: method must be 'auto', 'host' or 'device', not {method!r}")
    args = (lo, hi, max_leaf_size, n_bins, traversal_cost, intersection_cost, sah_samples, device)
    if method != "auto":
        return _build(*args, method, subtree_size)
    from ..errors import DeviceError

    try:
        return _build(*args, "auto", subtree_size)
    except DeviceError as exc:           # e.g. a driver that cannot build the kernel: the host build still works
        import logging

        logging.getLogger(__name__).warning("BVH build on the device failed, building on the host: %s", exc)
        return _build(*args, "host", subtree_size)


def _build(lo, hi, max_leaf_size, n_bins, traversal_cost, intersection_cost, sah_samples, spec, method,
           subtree_size):
    t0 = time.perf_counter()
    lo = np.ascontiguousarray(lo, np.float32).reshape(-1, 3)
    hi = np.ascontiguousarray(hi, np.float32).reshape(-1, 3)
    N = len(lo)
    max_leaf_size = max(1, int(max_leaf_size))
    n_bins = max(2, int(n_bins))
    sah_samples = max(int(sah_samples), 64)
    sample_above = 2 * sah_samples
    ct, ci = float(traversal_cost), float(intersection_cost)
    if N == 0:
        return BVH(_empty_nodes(), np.zeros(0, np.int64), 1, 0, time.perf_counter() - t0, 0.0, 0, 0)
    device = None
    if method == "device" or (method == "auto" and N >= DEVICE_MIN):
        from .bvh_device import device_context

        device = device_context(spec)
        if device is None and method == "device":
            from ..errors import DeviceError

            raise DeviceError("build_bvh(method='device'): no OpenCL device")
    if subtree_size is None:
        # A few tasks per compute unit balance the load; every level the host builds costs a pass over N.
        units = device[0].devices[0].max_compute_units if device is not None else 1
        subtree_size = max(DEVICE_SUBTREE_MIN, N // (DEVICE_TASKS_PER_UNIT * max(1, units)))
    tasks = []                                                  # nodes handed to the device, per level

    # The active set: primitives of the frontier nodes only, each node a contiguous run, in frontier order;
    # one float32 row per coordinate (doubled centroids are L + H, computed when needed).
    L = [np.ascontiguousarray(lo[:, a]) for a in range(3)]
    H = [np.ascontiguousarray(hi[:, a]) for a in range(3)]
    ids = np.arange(N, dtype=np.int64)
    order = np.empty(N, np.int64)
    force_depth = max(1, KERNEL_STACK_SIZE - math.ceil(math.log2(max(N, 2))) - 4)

    nodes = _Nodes()
    root_lo = np.array([x.min() for x in L], np.float32)
    root_hi = np.array([x.max() for x in H], np.float32)
    nodes.add(root_lo, root_hi, [0], [N], 0)
    # Frontier: node ids, starts in the final order, counts, boxes, doubled-centroid bounds.
    f_id, f_start, f_n = np.array([0]), np.array([0]), np.array([N])
    f_lo, f_hi = root_lo[None], root_hi[None]
    f_cmin = np.array([[x.min() for x in (L[a] + H[a] for a in range(3))]], np.float32)
    f_cmax = np.array([[x.max() for x in (L[a] + H[a] for a in range(3))]], np.float32)
    depth = 0
    while len(f_id):
        if device is not None:
            dev = f_n <= subtree_size
            if dev.any():
                # These nodes leave the active set; their subtrees are built on the device after the loop.
                m = _spreader(f_n)(dev)
                tasks.append(([x[m] for x in L], [x[m] for x in H], ids[m], f_id[dev], f_start[dev], f_n[dev],
                              np.full(int(dev.sum()), depth)))
                keep = ~m
                L, H, ids = [x[keep] for x in L], [x[keep] for x in H], ids[keep]
                f_id, f_start, f_n = f_id[~dev], f_start[~dev], f_n[~dev]
                f_lo, f_hi, f_cmin, f_cmax = f_lo[~dev], f_hi[~dev], f_cmin[~dev], f_cmax[~dev]
                if not len(f_id):
                    break
        F = len(f_id)
        M = len(ids)
        off = np.cumsum(f_n) - f_n
        rep = _spreader(f_n)                                    # per node -> per primitive
        seg = rep(np.arange(F))
        p_in = np.arange(M) - rep(off)
        small = (f_n >= 2) & (f_n <= DP_MAX)
        coincident = np.all(f_cmax <= f_cmin, axis=1)
        ev = (f_n > DP_MAX) & ~coincident & (depth + 1 < force_depth)
        nb = _node_bins(f_n, n_bins, sample_above)
        sampled = ev & (f_n > sample_above)
        if sampled.any():
            # Large nodes estimate their SAH from an evenly strided sample of their primitives.
            k = np.where(sampled, sah_samples, f_n)
            e_seg = np.repeat(np.arange(F), k)
            j = np.arange(k.sum()) - np.repeat(np.cumsum(k) - k, k)          # index within the node
            pos = off[e_seg] + np.where(sampled[e_seg], (j * f_n[e_seg]) // sah_samples, j)
        else:
            k, pos = f_n, None
        ext = f_cmax - f_cmin
        with np.errstate(divide="ignore", over="ignore"):
            # (1 - 2^-20) keeps the largest centroid in the last bin despite rounding.
            ok = ext > 1e-30
            scale = np.where(ok, (nb * (1.0 - 2.0 ** -20))[:, None] / np.where(ok, ext, 1), 0).astype(np.float32)
        C = [L[a] + H[a] for a in range(3)]
        cost, axis, plane, box, bins = _binned_splits(L, H, C, pos, k, np.where(ev, nb, 0), f_cmin, scale)
        planar = plane >= 0
        cost[sampled] *= f_n[sampled] / sah_samples     # sample counts -> estimated primitive counts

        area = _half_area(f_lo.astype(np.float64), f_hi.astype(np.float64))
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(area > 0, cost / area, np.where(np.isfinite(cost), f_n, np.inf))
        leaf = (f_n <= max_leaf_size) & (ci * f_n <= ct + ci * ratio) & ~small

        # Leaves retire from the active set; their primitives take their final places in the leaf order.
        leaf_el = rep(leaf)
        if leaf_el.any():
            order[f_start[seg[leaf_el]] + p_in[leaf_el]] = ids[leaf_el]
        # So do nodes of at most DP_MAX primitives: their whole subtree is built at once.
        for n in range(2, DP_MAX + 1):
            g = np.nonzero(small & (f_n == n))[0]
            if len(g):
                at = off[g][None, :] + np.arange(n)[:, None]             # (n, S) positions
                Lg = np.stack([np.take(L[a], at) for a in range(3)])
                Hg = np.stack([np.take(H[a], at) for a in range(3)])
                _small_subtrees(nodes, Lg, Hg, np.take(ids, at), f_id[g], f_start[g],
                                np.full(len(g), depth), order, max_leaf_size, ct, ci)
        sp = np.nonzero(~leaf & ~small)[0]
        if len(sp) == 0:
            break
        depth += 1

        # Left/right: the bin of the chosen axis (the binning computed the same float32 values), or the first
        # half of the range for nodes without a usable plane (coincident centroids, depth limit).
        if bins is not None:                            # every primitive was binned: reuse its bins
            bi = _select(rep(axis), bins)
        else:
            cv = _select(rep(axis), C)
            cm = f_cmin[np.arange(F), axis]
            sc = scale[np.arange(F), axis]
            bi = ((cv - rep(cm)) * rep(sc)).astype(np.int64)
        left = np.where(rep(planar), bi <= rep(plane), p_in < rep(f_n // 2))
        # Stable partition inside each node: left primitives keep their order, then the right ones.
        cl = np.cumsum(left)
        before = cl[off] - left[off]                    # lefts before each node
        n_left = cl[off + f_n - 1] - before
        rank_l = cl - left - rep(before)
        split = np.zeros(F, bool)
        split[sp] = True
        new_off = np.cumsum(np.where(split, f_n, 0)) - np.where(split, f_n, 0)
        dest = rep(new_off) + np.where(left, rank_l, rep(n_left) + p_in - rank_l)
        keep = rep(split)
        src = np.empty(int(keep.sum()), np.int64)
        src[dest[keep]] = np.nonzero(keep)[0]
        L = [np.take(x, src) for x in L]
        H = [np.take(x, src) for x in H]
        ids = np.take(ids, src)

        # Children tile the new active set: left then right of each split node.
        nl_sp = n_left[sp]
        c_n = np.stack([nl_sp, f_n[sp] - nl_sp], axis=1).ravel()
        c_off = np.cumsum(c_n) - c_n
        c_end = c_off + c_n
        c_lo = np.stack([box[0, sp], box[2, sp]], axis=1).reshape(-1, 3)
        c_hi = np.stack([box[1, sp], box[3, sp]], axis=1).reshape(-1, 3)
        # Children of sampled or unplanned splits: exact boxes from their primitives.
        inexact = np.repeat(sampled[sp] | ~planar[sp], 2)
        if inexact.any():
            ci_ = np.nonzero(inexact)[0]
            for a in range(3):
                c_lo[ci_, a] = _range_reduce(L[a], c_off[ci_], c_end[ci_], np.minimum)
                c_hi[ci_, a] = _range_reduce(H[a], c_off[ci_], c_end[ci_], np.maximum)
        c_cmin = np.empty_like(c_lo)
        c_cmax = np.empty_like(c_lo)
        for a in range(3):
            cc = L[a] + H[a]
            c_cmin[:, a] = np.minimum.reduceat(cc, c_off)
            c_cmax[:, a] = np.maximum.reduceat(cc, c_off)
        c_start = np.stack([f_start[sp], f_start[sp] + nl_sp], axis=1).ravel()
        lid = nodes.add_children(f_id[sp], c_lo[0::2], c_hi[0::2], c_lo[1::2], c_hi[1::2], f_start[sp], nl_sp,
                                 f_n[sp] - nl_sp, depth)
        f_id = np.stack([lid, lid + 1], axis=1).ravel()
        f_start, f_n = c_start, c_n
        f_lo, f_hi, f_cmin, f_cmax = c_lo, c_hi, c_cmin, c_cmax

    ext = _device_subtrees(device, tasks, order, max_leaf_size, ct, ci, force_depth) if tasks else None

    blo = np.concatenate(nodes.lo)
    bhi = np.concatenate(nodes.hi)
    bstart = np.concatenate(nodes.start)
    bcount = np.concatenate(nodes.count)
    bdepth = np.concatenate(nodes.depth)
    bleft = np.full(nodes.n, -1, np.int64)
    for (p, c) in nodes.links:
        bleft[p] = c
    nodes_arr, node_count = _flatten(blo, bhi, bstart, bcount, bleft, bdepth, ext)
    levels = int(bdepth.max()) + 1
    if ext is not None and len(ext[0]):
        levels = max(levels, int(ext[2].max()) + 1)
    sah, leaf_count, max_leaf_prims = _tree_stats(nodes_arr, ct, ci)
    return BVH(nodes=nodes_arr, order=order, node_count=node_count, depth=levels,
               build_seconds=time.perf_counter() - t0, sah_cost=sah, leaf_count=leaf_count,
               max_leaf_prims=max_leaf_prims)


def _tree_stats(nodes, ct, ci):
    """(SAH cost relative to the root box, leaves, most primitives in a leaf) of a flattened tree: every node
    but the root is one child slot, so one pass over the slots sees each once."""
    n = nodes.reshape(-1, 4, 4)
    lo, hi = n[:, 0::2, :3], n[:, 1::2, :3]                    # (K, 2, 3): slots A, B
    w = n.view(np.uint32)[:, :, 3]
    ref, cnt = w[:, 0::2], w[:, 1::2].astype(np.int64)
    leaf = (ref & np.uint32(LEAF_FLAG)) != 0
    area = _half_area(lo, hi).astype(np.float64)               # float32 per box, summed in float64
    root_lo, root_hi = lo[0].min(axis=0), hi[0].max(axis=0)
    counts = cnt[leaf]
    if len(n) == 1 and leaf.all() and cnt[0, 1] == 0:           # the root is a leaf (slot B empty)
        return float(ci * cnt[0, 0]), int(cnt[0, 0] > 0), int(cnt[0, 0])
    root_area = float(_half_area(root_lo.astype(np.float64), root_hi.astype(np.float64)))
    total = ct * root_area + ct * area[~leaf].sum() + ci * (area[leaf] * counts).sum()
    sah = total / (root_area if root_area > 0 else 1.0)
    return float(sah), int((counts > 0).sum()), int(counts.max()) if len(counts) else 0


def _device_subtrees(device, tasks, order, max_leaf, ct, ci, force_depth):
    """Build the subtrees of the handed-over nodes with the OpenCL kernel. Returns (binary node ids whose
    subtree is interior, their interior node counts, their deepest leaf's depth, their flattened nodes task
    after task); a task whose root became a leaf stays a leaf of the host's tree (its record already says so)."""
    from .bvh_device import build_subtrees

    cat = lambda i: np.concatenate([t[i] for t in tasks])      # noqa: E731
    L = [np.concatenate([t[0][a] for t in tasks]) for a in range(3)]
    H = [np.concatenate([t[1][a] for t in tasks]) for a in range(3)]
    ids, t_id, t_start, t_n, t_depth = cat(2), cat(3), cat(4), cat(5), cat(6)
    t_off = np.cumsum(t_n) - t_n
    pid, K, deepest, block = build_subtrees(device, L, H, ids, t_off, t_n, t_depth, t_start, max_leaf, ct, ci,
                                            force_depth)
    order[np.repeat(t_start - t_off, t_n) + np.arange(len(pid))] = pid
    has = K > 0
    return t_id[has], K[has], (t_depth + deepest)[has], block


def _flatten(blo, bhi, bstart, bcount, bleft, bdepth, ext=None):
    """Binary tree (any node order; right child = left + 1) -> depth-first 2-wide node table (module docstring).

    ``ext`` = (node ids, interior counts, -, flattened nodes) of subtrees built on the device: those nodes are
    interior, and their already flattened subtrees are placed (and their references moved) as a whole."""
    n = len(blo)
    inner = bleft >= 0
    bright = np.where(inner, bleft + 1, -1)
    size = inner.astype(np.int64)                                # interior nodes in each subtree
    is_ext = np.zeros(n, bool)
    if ext is not None:
        e_id, e_k = ext[0], ext[1]
        is_ext[e_id] = True
        size[e_id] = e_k
    if not inner[0] and not is_ext[0]:                          # the root is a leaf: leaf in A, empty slot in B
        nodes = _empty_nodes()
        u = nodes.view(np.uint32)
        nodes[0, :3], nodes[1, :3] = blo[0], bhi[0]
        u[0, 3] = LEAF_FLAG | np.uint32(bstart[0])
        u[1, 3] = bcount[0]
        nodes[2, :3], nodes[3, :3] = blo[0], bhi[0]
        return nodes, 1
    # Interior nodes of the host's tree, grouped by depth.
    ids = np.nonzero(inner)[0]
    ids = ids[np.argsort(bdepth[ids].astype(np.uint8), kind="stable")]
    bounds = np.searchsorted(bdepth[ids], np.arange(bdepth.max() + 2))
    levels = [ids[bounds[d]:bounds[d + 1]] for d in range(len(bounds) - 1)]
    for lv in reversed(levels):
        size[lv] += size[bleft[lv]] + size[bright[lv]]
    flat = np.full(n, -1, np.int64)
    flat[0] = 0
    for lv in levels:
        flat[bleft[lv]] = flat[lv] + 1
        flat[bright[lv]] = flat[lv] + 1 + size[bleft[lv]]
    K = int(size[0])
    nodes = np.zeros((K, 4, 4), np.float32)
    u = nodes.view(np.uint32)
    rows = flat[ids]
    for slot, child in ((0, bleft[ids]), (2, bright[ids])):
        nodes[rows, slot, :3] = blo[child]
        nodes[rows, slot + 1, :3] = bhi[child]
        leafc = ~inner[child] & ~is_ext[child]
        ref = np.where(leafc, bstart[child] | LEAF_FLAG, flat[child])
        u[rows, slot, 3] = ref.astype(np.uint32)
        u[rows, slot + 1, 3] = np.where(leafc, bcount[child], 0).astype(np.uint32)
    if ext is not None and len(e_id):
        block = ext[3].reshape(-1, 4, 4)
        # Interior references are local to their subtree: move them to where the subtree now starts.
        w = block.view(np.uint32)[:, 0::2, 3]
        w += np.where((w & np.uint32(LEAF_FLAG)) == 0, np.repeat(flat[e_id], e_k)[:, None], 0).astype(np.uint32)
        src = np.cumsum(e_k) - e_k
        for f, a, k in zip(flat[e_id], src, e_k):                # a few tasks per compute unit: slices
            nodes[f:f + k] = block[a:a + k]
    return nodes.reshape(4 * K, 4), K

