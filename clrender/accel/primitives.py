"""Primitive bounds and the packed primitive table the traversal kernels read.

Two primitive kinds share one index space: triangles first (ids 0..T-1), then analytic spheres (ids 0..S-1,
told apart by bit 31 of the id word). The BVH is built over the boxes from :func:`primitive_bounds` and the
kernel reads primitives in BVH leaf order from :func:`pack_primitives`, three ``float4`` rows each:

======== ================================ ================== ==============
kind     row 0                            row 1              row 2
======== ================================ ================== ==============
triangle ``v0.xyz, as_float(i)``          ``v1.xyz, 0``      ``v2.xyz, 0``
sphere   ``center.xyz, as_float(j|2^31)`` ``radius, 0, 0, 0`` ``0, 0, 0, 0``
======== ================================ ================== ==============

in float32. The vertices themselves, not edges, so that a vertex shared by several triangles is the same
float in each: the watertight test (kernels/bvh_common.h) relies on it. An empty table has shape
(0, 4); OpenCL cannot allocate a zero-size buffer, so callers upload at least one (unused) row.
"""
from __future__ import annotations

import numpy as np

from ..device.layout import ENUMS

SPHERE_FLAG = np.uint32(ENUMS["BVH_SPHERE_BIT"])


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


def primitive_bounds(tri_v0, tri_v1, tri_v2, spheres):
    """Axis-aligned boxes of all primitives, triangles first: ``(lo, hi)`` float32 arrays of shape (T+S, 3)."""
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
    lo = np.concatenate([tlo, slo]).astype(np.float32, copy=False)
    hi = np.concatenate([thi, shi]).astype(np.float32, copy=False)
    return np.ascontiguousarray(lo), np.ascontiguousarray(hi)


def pack_primitives(tri_v0, tri_v1, tri_v2, spheres, order):
    """The primitive table in leaf ``order`` (ids < T are triangles, the rest spheres): float32 (3*N, 4)."""
    v0, v1, v2 = _as3(tri_v0, "tri_v0"), _as3(tri_v1, "tri_v1"), _as3(tri_v2, "tri_v2")
    s = _spheres(spheres)
    T, S = len(v0), len(s)
    order = np.asarray(order, dtype=np.int64)
    if order.shape != (T + S,):
        raise ValueError(f"order must list all {T + S} primitives, got shape {order.shape}")
    out = np.zeros((T + S, 3, 4), np.float32)
    bits = out.view(np.uint32)
    tri = order < T
    ti = order[tri]
    out[tri, 0, :3] = np.asarray(v0, np.float32)[ti]
    out[tri, 1, :3] = np.asarray(v1, np.float32)[ti]
    out[tri, 2, :3] = np.asarray(v2, np.float32)[ti]
    bits[tri, 0, 3] = ti.astype(np.uint32)
    sj = order[~tri] - T
    out[~tri, 0, :3] = s[sj, :3]
    out[~tri, 1, 0] = np.abs(s[sj, 3])
    bits[~tri, 0, 3] = sj.astype(np.uint32) | SPHERE_FLAG
    return out.reshape(3 * (T + S), 4)
