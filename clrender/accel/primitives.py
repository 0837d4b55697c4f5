"""Primitive bounds and the packed primitive table the traversal kernels read.

Three primitive kinds share one index space: triangles first (ids 0..T-1), then analytic spheres (ids 0..S-1,
told apart by bit 31 of the id word), then the voxels of SDF grids that hold a piece of their surface
(:class:`SdfVoxels`; bit 31 and bit 30 of the id word, whose other bits name the voxel's shape). The BVH is built over the boxes from :func:`primitive_bounds`; the
kernels read the primitives in BVH leaf order from :func:`pack_leaf_blocks` (the same words, 40 bytes each,
blocked by leaf so that four are tested at once). :func:`pack_primitives` gives them one per row, three
``float4`` rows each (what the tests' reference tracer reads):

======== ================================ ================== ==============
kind     row 0                            row 1              row 2
======== ================================ ================== ==============
triangle ``v0.xyz, as_float(i)``          ``v1.xyz, 0``      ``v2.xyz, 0``
sphere   ``center.xyz, as_float(j|2^31)`` ``radius, 0, 0, 0`` ``0, 0, 0, 0``
======== ================================ ================== ==============

(an SDF voxel has no row there: only the device's table below knows them) in float32 (pack_scene gives triangles their :func:`leaf_refs` as id words instead of their numbers, so that a
hit says where the vertices are: the device keeps no other copy of them). The vertices themselves, not edges,
so that a vertex shared by several triangles is the same float in each: the watertight test
(kernels/bvh_common.h) relies on it. An empty table has shape
(0, 4); OpenCL cannot allocate a zero-size buffer, so callers upload at least one (unused) row.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..device.layout import ENUMS

SPHERE_FLAG = np.uint32(ENUMS["BVH_SPHERE_BIT"])
SDF_FLAG = np.uint32(ENUMS["BVH_SDF_BIT"])      # with SPHERE_FLAG: an SDF grid's voxel (kernels/bvh_common.h)
LEAF_FLAG = np.uint32(ENUMS["BVH_LEAF_BIT"])   # a node's reference to a leaf (clrender.accel.bvh writes them)


def _as3(a, name):
    a = np.zeros((0, 3)) if a is None else np.asarray(a)
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"{name} must have shape (T, 3), got {a.shape}")
    return a


def _spheres(spheres):
    s = np.zeros((0, 4)) if spheres is None else np.asarray(spheres)
    if s.ndim != 2 or s.shape[1] != 4:
        raise ValueError(f"spheres must have shape (S, 4) = center xyz, radius; got {s.shape}")
    return s


@dataclass
class SdfVoxels:
    """The voxels of SDF grids that the BVH holds (clrender/shapes/sdfgrid.py adds them), V of them:

    ``lo``, ``hi``: (V, 3) world-space boxes; ``corners``: (V, 8) the grid's values at the voxel's corners, corner
    x + 2 y + 4 z; ``to_voxel``: (V, 3, 4) the affine map from the world to the voxel's own unit cube; ``shape``:
    (V,) the shape each belongs to."""
    lo: np.ndarray
    hi: np.ndarray
    corners: np.ndarray
    to_voxel: np.ndarray
    shape: np.ndarray

    @staticmethod
    def empty() -> "SdfVoxels":
        return SdfVoxels(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.float32), np.zeros((0, 8), np.float32),
                         np.zeros((0, 3, 4), np.float32), np.zeros(0, np.uint32))

    @staticmethod
    def concatenate(parts) -> "SdfVoxels":
        parts = list(parts)
        if not parts:
            return SdfVoxels.empty()
        return SdfVoxels(*(np.concatenate([getattr(p, f) for p in parts]) for f in
                           ("lo", "hi", "corners", "to_voxel", "shape")))

    def __len__(self) -> int:
        return len(self.shape)


def primitive_bounds(tri_v0, tri_v1, tri_v2, spheres, voxels: SdfVoxels | None = None):
    """Axis-aligned boxes of all primitives, triangles first, then spheres, then SDF voxels: ``(lo, hi)`` float32
    arrays of shape (T+S+V, 3)."""
    v0, v1, v2 = _as3(tri_v0, "tri_v0"), _as3(tri_v1, "tri_v1"), _as3(tri_v2, "tri_v2")
    if not (len(v0) == len(v1) == len(v2)):
        raise ValueError("tri_v0, tri_v1 and tri_v2 must have the same length")
    s = _spheres(spheres)
    # Vertices are stored as float32 on the device, so the box of the float32 vertices is exact.
    f0, f1, f2 = (np.asarray(v, np.float32) for v in (v0, v1, v2))
    tlo = np.minimum(np.minimum(f0, f1), f2)
    thi = np.maximum(np.maximum(f0, f1), f2)
    c = s[:, :3].astype(np.float64)
    r = np.abs(s[:, 3:4].astype(np.float64))
    # Rounding c ± r to float32 may land inside the sphere; step one ulp outward so the box stays conservative.
    slo = np.nextafter((c - r).astype(np.float32), np.float32(-np.inf))
    shi = np.nextafter((c + r).astype(np.float32), np.float32(np.inf))
    vox = voxels if voxels is not None else SdfVoxels.empty()
    lo = np.concatenate([tlo, slo, np.asarray(vox.lo, np.float32)]).astype(np.float32, copy=False)
    hi = np.concatenate([thi, shi, np.asarray(vox.hi, np.float32)]).astype(np.float32, copy=False)
    return np.ascontiguousarray(lo), np.ascontiguousarray(hi)


def pack_primitives(tri_v0, tri_v1, tri_v2, spheres, order):
    """The primitive table in leaf ``order`` (ids < T are triangles, the rest spheres): float32 (3*N, 4)."""
    words = _leaf_order_words(tri_v0, tri_v1, tri_v2, spheres, order)
    out = np.zeros((len(words), 3, 4), np.uint32)
    out[:, 0, :3], out[:, 1, :3], out[:, 2, :3] = words[:, 0:3], words[:, 3:6], words[:, 6:9]
    out[:, 0, 3] = words[:, 9]
    return out.view(np.float32).reshape(-1, 4)


def _leaf_order_words(tri_v0, tri_v1, tri_v2, spheres, order, tri_ids=None, voxels=None, voxel_records=0):
    """Ten uint32 words per primitive, in leaf ``order`` (float bits and ids alike: ids are not floats)::

        triangle: v0.xyz, v1.xyz, v2.xyz, id (its number, or tri_ids[number])
        sphere j: centre.xyz, |radius|, 0 x 5, j | SPHERE_FLAG
        voxel v:  its 8 corner values, the word offset of its to_voxel map (voxel_records + 12 v),
                  shape | SPHERE_FLAG | SDF_FLAG

    built in id order and moved into leaf order by one gather of whole rows."""
    v0, v1, v2 = _as3(tri_v0, "tri_v0"), _as3(tri_v1, "tri_v1"), _as3(tri_v2, "tri_v2")
    sph = _spheres(spheres)
    vox = voxels if voxels is not None else SdfVoxels.empty()
    T, S, V = len(v0), len(sph), len(vox)
    order = np.asarray(order, dtype=np.int64)
    if order.shape != (T + S + V,):
        raise ValueError(f"order must list all {T + S + V} primitives, got shape {order.shape}")
    if np.any(np.asarray(vox.shape, np.uint32) >= SDF_FLAG):
        raise ValueError("an SDF voxel's shape number must be below 2^30")
    prim = np.zeros((T + S + V, BLOCK_WORDS), np.uint32)
    f = prim.view(np.float32)
    f[:T, 0:3], f[:T, 3:6], f[:T, 6:9] = v0, v1, v2
    if tri_ids is None:
        prim[:T, 9] = np.arange(T, dtype=np.uint32)
    else:
        tri_ids = np.asarray(tri_ids, np.uint32)
        if tri_ids.shape != (T,):
            raise ValueError(f"tri_ids must have one word per triangle ({T}), got shape {tri_ids.shape}")
        prim[:T, 9] = tri_ids
    f[T:T + S, 0:3] = sph[:, :3]
    f[T:T + S, 3] = np.abs(sph[:, 3])
    prim[T:T + S, 9] = np.arange(S, dtype=np.uint32) | SPHERE_FLAG
    f[T + S:, 0:8] = vox.corners
    prim[T + S:, 8] = voxel_records + VOXEL_RECORD_WORDS * np.arange(V, dtype=np.uint32)
    prim[T + S:, 9] = np.asarray(vox.shape, np.uint32) | SPHERE_FLAG | SDF_FLAG
    return prim[order]


# ---------------------------------------------------------------------------------------- the device's table
BLOCK_LANES = 4        # primitives tested together, one per float4 lane (kernels/bvh_common.h)
# build_bvh options for this table: with up to four primitives tested at the price of about one, a leaf of
# 3-4 beats another node level more often than the builder's default cost ratio (1) says. Measured in
# benchmarks/README.md ("Trace speed and memory"): faster on the Cornell twin and the 1 M mesh, and half
# the nodes.
BUILD_OPTIONS = {"traversal_cost": 2.5}
# and over 8-wide nodes (the default), leaves of up to 6 (two blocks): the same speed within noise (Cornell
# twin x1.07 and x0.96, 1 M mesh x1.05 and x1.10 in two interleaved runs) with a fifth fewer nodes (1.3 M
# blob: 28.9 -> 23.4 device bytes per triangle of nodes).
BUILD_OPTIONS_BY_WIDTH = {8: {"max_leaf_size": 6}}
BLOCK_WORDS = 10       # words per primitive: v0.xyz, v1.xyz, v2.xyz, id
VOXEL_RECORD_WORDS = 12   # an SDF voxel's to_voxel map, after the blocks (kernels/bvh_common.h bvh_isect_voxel)


def bvh_leaves(bvh):
    """``(first, count)`` int64 arrays of the leaves of a binary BVH (``BVH.nodes`` of clrender.accel.bvh)."""
    u = np.asarray(bvh.nodes).reshape(-1, 4, 4).view(np.uint32)
    ref = u[:, [0, 2], 3].reshape(-1)
    cnt = u[:, [1, 3], 3].reshape(-1).astype(np.int64)
    leaf = ((ref & LEAF_FLAG) != 0) & (cnt > 0)
    return (ref[leaf] & ~LEAF_FLAG).astype(np.int64), cnt[leaf]


def _block_of(n, leaf_first, leaf_count):
    """Per leaf-order position 0..n-1: the start s of its block, the block's size c and its lane (see
    :func:`pack_leaf_blocks`); checks that the leaves cover the n positions exactly once."""
    first = np.asarray(leaf_first, np.int64)
    count = np.asarray(leaf_count, np.int64)
    if count.sum() != n or (n and not np.array_equal(np.sort(first), np.concatenate([[0], np.cumsum(
            count[np.argsort(first)])[:-1]]))):
        raise ValueError(f"the leaves must cover the {n} primitives of the leaf order exactly once")
    # Per leaf-order position: its leaf's first and count, then its block's start s, size c and lane l.
    lf = np.repeat(first, count)
    lc = np.repeat(count, count)
    pos = np.repeat(first - np.cumsum(np.concatenate([[0], count[:-1]])), count) + np.arange(n)
    rel = pos - lf
    s = lf + rel // BLOCK_LANES * BLOCK_LANES
    c = np.minimum(BLOCK_LANES, lf + lc - s)
    out_s, out_c = np.empty(n, np.int64), np.empty(n, np.int64)
    out_s[pos], out_c[pos] = s, c
    return out_s, out_c, np.arange(n) - out_s


def leaf_refs(leaf_first, leaf_count):
    """The leaf reference of every leaf-order position (layout.ENUMS PRIM_REF_*): ``pos << 4 | lane << 2 |
    (c - 1)``, uint32; what :func:`pack_leaf_blocks` writes as a triangle's id word when given them as
    ``tri_ids``, so that a hit names where the triangle's vertices are (kernels/shapes/mesh.h mesh_triangle)."""
    n = int(np.sum(leaf_count))
    if n - 1 > ENUMS["PRIM_REF_MAX_POS"]:
        raise ValueError(f"{n} primitives: leaf references address at most {ENUMS['PRIM_REF_MAX_POS'] + 1}")
    s, c, lane = _block_of(n, leaf_first, leaf_count)
    pos = np.arange(n, dtype=np.int64)
    return (pos << ENUMS["PRIM_REF_POS_SHIFT"] | lane << 2 | (c - 1)).astype(np.uint32)


def pack_leaf_blocks(tri_v0, tri_v1, tri_v2, spheres, order, leaf_first, leaf_count, tri_ids=None, voxels=None):
    """The primitive table the traversal kernels read: ``BLOCK_WORDS`` (40 bytes) per primitive, in leaf
    ``order``, as float32 rows of 4 (padded so that a 4-float load at any row start stays inside).

    Each leaf (``leaf_first``, ``leaf_count``: ranges of the leaf order, e.g. from :func:`bvh_leaves`) is cut
    into blocks of up to ``BLOCK_LANES`` primitives; a block of c primitives starting at leaf-order position s
    takes words 10 s .. 10 (s + c) - 1 as ten rows of c words, structure of arrays::

        row 0..2: v0.x, v0.y, v0.z of its primitives    row 3..5: v1.xyz    row 6..8: v2.xyz    row 9: id

    so word 10 s + r c + l is row r of lane l, and one 4-float load per row feeds all lanes (lanes >= c are
    read but ignored). A sphere lane holds its centre in rows 0..2 and its radius in row 3; the id word is
    as in :func:`pack_primitives` (sphere ids have bit 31 set). 40 bytes per primitive, no padding, and a
    block's 10 c words are contiguous: the same cache lines as the 3-row table of :func:`pack_primitives`,
    one ``float4`` per primitive fewer.

    ``tri_ids`` (uint32, one per triangle id) replaces the triangles' id words; pack_scene gives the triangles'
    :func:`leaf_refs`. Spheres keep theirs.

    ``voxels`` (:class:`SdfVoxels`): each voxel's row holds its corner values in rows 0..7 and in row 8 the word
    offset of its record, ``VOXEL_RECORD_WORDS`` words after the blocks: the rows of its to_voxel map."""
    vox = voxels if voxels is not None else SdfVoxels.empty()
    n = len(np.asarray(order))
    blocks = ((BLOCK_WORDS * n + BLOCK_LANES) // 4 + 1) * 4
    words = _leaf_order_words(tri_v0, tri_v1, tri_v2, spheres, order, tri_ids, vox, blocks)
    s, c, lane = _block_of(n, leaf_first, leaf_count)
    out = np.zeros(blocks + VOXEL_RECORD_WORDS * len(vox), np.uint32)
    at = BLOCK_WORDS * s[:, None] + np.arange(BLOCK_WORDS)[None, :] * c[:, None] + lane[:, None]
    out[at] = words
    out[blocks:].view(np.float32)[:] = np.asarray(vox.to_voxel, np.float32).reshape(-1)
    return out.view(np.float32).reshape(-1, 4)
