"""BVH build invariants on the host, and kernels/bvh.h traversal against a float64 brute-force reference."""
from pathlib import Path

import numpy as np
import pytest

from clrender.accel.bvh import LEAF_FLAG, build_bvh
from clrender.accel.primitives import (SPHERE_FLAG, bvh_leaves, leaf_refs, pack_leaf_blocks, pack_primitives,
                                       primitive_bounds)

LOCAL = 64

TRACE_SRC = r"""
#include "bvh.h"
/* org.w = tmin, dir.w = tmax. out = (t, u, v, found); prim = id word or ~0; any = any-hit flag. */
__kernel void trace(__global const float4* nodes, __global const float4* prims, __global const float4* org,
                    __global const float4* dir, uint n, __global float4* out, __global uint* prim,
                    __global int* any) {
    uint i = get_global_id(0);
    if (i >= n) return;   /* the global size is padded to a multiple of the local size */
    float4 o = org[i], d = dir[i];
    Hit h;
    bool f = bvh_closest_hit(nodes, prims, vxyz(o), vxyz(d), o.w, d.w, &h);
    out[i] = f ? (float4)(h.t, h.u, h.v, 1.0f) : (float4)(0.0f);
    prim[i] = f ? h.prim : 0xffffffffu;
    any[i] = bvh_any_hit(nodes, prims, vxyz(o), vxyz(d), o.w, d.w) ? 1 : 0;
}
"""


# ---------------------------------------------------------------------------------------------- scenes
def random_soup(rng, n, spread=1.0, size=0.3):
    c = rng.uniform(-spread, spread, (n, 1, 3))
    v = c + rng.normal(0, size, (n, 3, 3))
    return v[:, 0], v[:, 1], v[:, 2]


def random_spheres(rng, n, spread=1.0):
    s = np.empty((n, 4))
    s[:, :3] = rng.uniform(-spread, spread, (n, 3))
    s[:, 3] = rng.uniform(0.05, 0.4, n)
    return s


def icosphere(level, radius=1.0):
    t = (1 + 5 ** 0.5) / 2
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
             (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = np.array(verts, float)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    tri = v[np.array(faces)]                                    # (F, 3, 3)
    for _ in range(level):
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        ab, bc, ca = [(x + y) / np.linalg.norm(x + y, axis=1, keepdims=True) for x, y in ((a, b), (b, c), (c, a))]
        tri = np.concatenate([np.stack(f, 1) for f in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    tri = tri * radius
    return tri[:, 0], tri[:, 1], tri[:, 2]


def random_rays(rng, n, spread=1.5, zero_components=False):
    o = rng.uniform(-spread, spread, (n, 3))
    d = rng.normal(size=(n, 3)) * rng.uniform(0.1, 10.0, (n, 1))     # deliberately not normalised
    if zero_components:
        # Axis-aligned rays: one or two exact zeros (including -0.0) per direction.
        k = rng.integers(1, 3, n)
        for i in range(n):
            ax = rng.choice(3, k[i], replace=False)
            d[i, ax] = rng.choice([0.0, -0.0], k[i])
    tmin = np.where(rng.random(n) < 0.5, 0.0, rng.uniform(0, 0.5, n))
    tmax = np.where(rng.random(n) < 0.5, np.inf, rng.uniform(0.1, 3.0, n))
    return o, d, tmin, tmax


# ------------------------------------------------------------------------------------------- reference
def reference(prims, o, d, tmin, tmax):
    """Brute-force closest hit in float64 over the packed primitive table (any order).

    Returns (t, id word, u, v, ambiguous, tie): ambiguous rays are those whose answer float32 rounding may
    legitimately change (grazing an edge or sphere silhouette, a hit at tmin/tmax, an ill-conditioned hit);
    tie marks rays whose two nearest hits are too close to tell which primitive is first.
    """
    P = prims.reshape(-1, 3, 4).astype(np.float64)
    ids = prims.reshape(-1, 3, 4)[:, 0, 3].view(np.uint32)
    sph = (ids & SPHERE_FLAG) != 0
    o, d = o.astype(np.float32).astype(np.float64), d.astype(np.float32).astype(np.float64)
    tmin, tmax = tmin.astype(np.float32).astype(np.float64), tmax.astype(np.float32).astype(np.float64)
    tri_i, sph_i = np.nonzero(~sph)[0], np.nonzero(sph)[0]
    with np.errstate(all="ignore"):   # degenerate pairs give inf/nan on purpose; the masks drop them
        return _reference(P, ids, tri_i, sph_i, o, d, tmin, tmax)


def _reference(P, ids, tri_i, sph_i, o, d, tmin, tmax):
    R = len(o)
    best_t = np.full(R, np.inf)
    best_id = np.full(R, 0xFFFFFFFF, np.uint32)
    best_u = np.zeros(R)
    best_v = np.zeros(R)
    flag_t = np.full(R, np.inf)          # smallest t among pairs whose outcome is uncertain
    second_t = np.full(R, np.inf)        # for ties: the second-best accepted t
    R = len(o)
    chunk = max(1, 400_000 // max(1, len(P)))
    for r0 in range(0, R, chunk):
        sl = slice(r0, min(R, r0 + chunk))
        oo, dd = o[sl, None, :], d[sl, None, :]
        lo_t, hi_t = tmin[sl, None], tmax[sl, None]
        tol = lambda t: 1e-4 * np.maximum(1.0, np.abs(t))  # noqa: E731
        cand_t, cand_u, cand_v, cand_id, cand_flag = [], [], [], [], []
        if len(tri_i):
            v0, e1, e2 = P[tri_i, 0, :3][None], P[tri_i, 1, :3][None], P[tri_i, 2, :3][None]
            e1, e2 = e1 - v0, e2 - v0               # rows 1 and 2 hold v1 and v2
            p = np.cross(dd, e2)
            det = np.sum(e1 * p, -1)
            with np.errstate(divide="ignore", invalid="ignore"):
                inv = 1.0 / det
                s = oo - v0
                u = np.sum(s * p, -1) * inv
                q = np.cross(s, e1)
                v = np.sum(dd * q, -1) * inv
                t = np.sum(e2 * q, -1) * inv
            margin = np.minimum(np.minimum(u, v), 1 - u - v)
            ok = (det != 0) & (margin >= 0) & (t > lo_t) & (t < hi_t)
            scale = np.linalg.norm(dd, axis=-1) * np.linalg.norm(e1, axis=-1) * np.linalg.norm(e2, axis=-1)
            near = (det != 0) & (margin > -1e-4) & (t > lo_t - tol(lo_t)) & (t < hi_t + tol(t))
            shaky = near & ((margin < 1e-4) | (np.abs(t - lo_t) < tol(lo_t)) | (np.abs(t - hi_t) < tol(t))
                            | (np.abs(det) < 1e-4 * scale))
            cand_t.append(np.where(ok, t, np.inf)); cand_u.append(u); cand_v.append(v)
            cand_id.append(np.broadcast_to(ids[tri_i][None], t.shape)); cand_flag.append(np.where(shaky, t, np.inf))
        if len(sph_i):
            c, r = P[sph_i, 0, :3][None], P[sph_i, 1, 0][None]
            f = oo - c
            a = np.sum(dd * dd, -1)
            b = np.sum(f * dd, -1)
            with np.errstate(divide="ignore", invalid="ignore"):
                l2 = np.sum((f - (b / a)[..., None] * dd) ** 2, -1)
                disc = a * (r * r - l2)
                sq = np.sqrt(np.maximum(disc, 0))
                t0, t1 = (-b - sq) / a, (-b + sq) / a
            hit = disc >= 0
            ok0 = hit & (t0 > lo_t) & (t0 < hi_t)
            ok1 = hit & (t1 > lo_t) & (t1 < hi_t)
            t = np.where(ok0, t0, np.where(ok1, t1, np.inf))
            graze = np.abs(r * r - l2) < 1e-4 * r * r
            bound = hit & ((np.abs(t0 - lo_t) < tol(lo_t)) | (np.abs(t1 - lo_t) < tol(lo_t))
                           | (np.abs(t0 - hi_t) < tol(t0)) | (np.abs(t1 - hi_t) < tol(t1)))
            fl = np.where(bound, np.minimum(np.abs(t0), np.abs(t1)), np.inf)
            fl = np.where(graze, np.where(np.isfinite(-b / a), np.abs(-b / a), np.inf), fl)
            cand_t.append(t); cand_u.append(np.zeros_like(t)); cand_v.append(np.zeros_like(t))
            cand_id.append(np.broadcast_to(ids[sph_i][None], t.shape)); cand_flag.append(fl)
        if not cand_t:
            continue
        T = np.concatenate(cand_t, 1)
        U, V = np.concatenate(cand_u, 1), np.concatenate(cand_v, 1)
        I, FL = np.concatenate(cand_id, 1), np.concatenate(cand_flag, 1)
        k = np.argmin(T, axis=1)
        rows = np.arange(T.shape[0])
        best_t[sl], best_id[sl] = T[rows, k], I[rows, k]
        best_u[sl], best_v[sl] = U[rows, k], V[rows, k]
        T2 = T.copy()
        T2[rows, k] = np.inf
        second_t[sl] = T2.min(axis=1)
        flag_t[sl] = FL.min(axis=1)
    best_id[~np.isfinite(best_t)] = 0xFFFFFFFF
    amb = np.isfinite(flag_t) & (flag_t <= np.where(np.isfinite(best_t),
                                                    best_t + 1e-3 * np.maximum(1, np.abs(best_t)), np.inf))
    with np.errstate(invalid="ignore"):
        tie = second_t - best_t <= 1e-4 * np.maximum(1, np.abs(best_t))
    return best_t, best_id, best_u, best_v, amb, tie


# ---------------------------------------------------------------------------------------------- device
class Tracer:
    """A traversal kernel (kernels/bvh.h or kernels/bvh4.h) and the node width its BVH must be given in."""

    def __init__(self, kernel, width):
        self.kernel, self.width = kernel, width


def make_tracer(ctx, width, defines=None):
    import pyopencl as cl

    from clrender.device.program import build_program

    src = TRACE_SRC if width == 2 else TRACE_SRC.replace('#include "bvh.h"', f'#include "bvh{width}.h"')
    return Tracer(cl.Kernel(build_program(ctx, src, defines=defines), "trace"), width)


def wide_nodes(bvh, width):
    """The node table the kernel of `width` reads (the binary tree itself for 2)."""
    if width == 2:
        return bvh
    from clrender.accel.bvh4 import collapse_bvh4
    from clrender.device.layout import ENUMS

    return _Nodes(collapse_bvh4(bvh, ENUMS[f"BVH{width}_STACK_SIZE"], width=width).nodes)


@pytest.fixture(scope="module", params=[(2, None), (4, None), (8, None), (8, {"BVH_PORTABLE_BITS": 1})],
                ids=["bvh2", "bvh4", "bvh8", "bvh8-portable"])
def trace_kernel(ctx, request):
    """Every traversal test below runs against the 2-, 4- and 8-wide kernels; the 8-wide one also with the
    portable child masks that devices other than PoCL on x86 use (kernels/bvh8.h bvh8_bits)."""
    return make_tracer(ctx, *request.param)


def device_trace(ctx, queue, kernel, bvh, prims, o, d, tmin, tmax):
    import pyopencl as cl

    R = len(o)
    G = max(LOCAL, -(-R // LOCAL) * LOCAL)
    org = np.zeros((G, 4), np.float32)
    dir_ = np.zeros((G, 4), np.float32)
    org[:R, :3], org[:R, 3] = o, tmin
    dir_[:R, :3], dir_[:R, 3] = d, tmax
    if len(prims) == 0:
        prims = np.zeros((3, 4), np.float32)    # OpenCL has no zero-size buffers
    mf = cl.mem_flags
    buf = lambda a: cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(a))  # noqa
    out = np.zeros((G, 4), np.float32)
    prim = np.zeros(G, np.uint32)
    any_ = np.zeros(G, np.int32)
    b_out = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
    b_prim = cl.Buffer(ctx, mf.WRITE_ONLY, prim.nbytes)
    b_any = cl.Buffer(ctx, mf.WRITE_ONLY, any_.nbytes)
    kernel(queue, (G,), (LOCAL,), buf(bvh.nodes), buf(prims), buf(org), buf(dir_), np.uint32(R),
           b_out, b_prim, b_any)
    cl.enqueue_copy(queue, out, b_out)
    cl.enqueue_copy(queue, prim, b_prim)
    cl.enqueue_copy(queue, any_, b_any)
    return out[:R], prim[:R], any_[:R]


def build_scene(v0, v1, v2, spheres, **kw):
    lo, hi = primitive_bounds(v0, v1, v2, spheres)
    bvh = build_bvh(lo, hi, **kw)
    return bvh, pack_leaf_blocks(v0, v1, v2, spheres, bvh.order, *bvh_leaves(bvh))


class _Nodes:
    def __init__(self, nodes):
        self.nodes = nodes


def check_trace(ctx, queue, tracer, v0, v1, v2, spheres, o, d, tmin, tmax, max_ambiguous=0.02, **kw):
    bvh, prims = build_scene(v0, v1, v2, spheres, **kw)
    bounds = primitive_bounds(v0, v1, v2, spheres)
    check_invariants(bvh, *bounds, kw.get("max_leaf_size", 4))
    tree = bvh
    if tracer.width == 4:
        from clrender.accel.bvh4 import collapse_bvh4
        from test_bvh4 import check_invariants4

        b4 = collapse_bvh4(bvh)
        check_invariants4(b4, *bounds, bvh.order, kw.get("max_leaf_size", 4))
        tree = _Nodes(b4.nodes)
    elif tracer.width == 8:
        from clrender.accel.bvh4 import collapse_bvh4
        from clrender.device.layout import ENUMS
        from test_bvh4 import check_invariants4

        b8 = collapse_bvh4(bvh, ENUMS["BVH8_STACK_SIZE"], width=8)
        check_invariants4(b8, *bounds, bvh.order, kw.get("max_leaf_size", 4), width=8)
        tree = _Nodes(b8.nodes)
    out, prim, any_ = device_trace(ctx, queue, tracer.kernel, tree, prims, o, d, tmin, tmax)
    return compare_with_reference(out, prim, any_, v0, v1, v2, spheres, o, d, tmin, tmax, max_ambiguous)


def compare_with_reference(out, prim, any_, v0, v1, v2, spheres, o, d, tmin, tmax, max_ambiguous=0.02):
    """The device's closest hits (t, primitive, barycentrics) and any-hits against the float64 brute force;
    rays whose answer float32 rounding may legitimately change are left out (and must be few)."""
    ref_prims = pack_primitives(v0, v1, v2, spheres, np.arange(len(primitive_bounds(v0, v1, v2, spheres)[0])))
    t, pid, u, v, amb, tie = reference(ref_prims, o, d, tmin, tmax)
    found = out[:, 3] > 0
    ref_found = np.isfinite(t)
    assert amb.mean() <= max_ambiguous, f"too many ambiguous rays ({amb.mean():.3f}); test scene is badly chosen"
    ok = ~amb
    bad = ok & (found != ref_found)
    assert not bad.any(), f"{bad.sum()} rays disagree on hit/miss, e.g. ray {np.nonzero(bad)[0][:5]}"
    both = ok & found
    tol = 1e-4 * np.maximum(1.0, np.abs(t[both]))
    err = np.abs(out[both, 0] - t[both])
    assert (err <= tol).all(), f"t differs by up to {err.max()}"
    same = both & ~tie
    assert np.array_equal(prim[same], pid[same]), f"{(prim[same] != pid[same]).sum()} rays hit the wrong primitive"
    trih = same & ((pid & SPHERE_FLAG) == 0)
    assert np.allclose(out[trih, 1], u[trih], atol=1e-3) and np.allclose(out[trih, 2], v[trih], atol=1e-3)
    assert np.array_equal(any_[ok].astype(bool), ref_found[ok]), "any-hit disagrees with closest-hit presence"
    # Whatever the ambiguity, the kernel must agree with itself.
    assert np.array_equal(any_.astype(bool), found) or (any_.astype(bool) != found)[~amb].sum() == 0
    return found, ref_found


# -------------------------------------------------------------------------------------- host invariants
def check_invariants(bvh, lo, hi, max_leaf):
    N = len(lo)
    assert np.array_equal(np.sort(bvh.order), np.arange(N)), "order is not a permutation"
    nodes = bvh.nodes.reshape(-1, 4, 4)
    assert len(nodes) == bvh.node_count
    w = nodes.view(np.uint32)[:, :, 3]
    slo = nodes[:, [0, 2], :3]                                    # (K, 2, 3)
    shi = nodes[:, [1, 3], :3]
    ref, cnt = w[:, [0, 2]], w[:, [1, 3]]
    leaf = (ref & LEAF_FLAG) != 0
    inner = ~leaf
    assert (cnt[inner] == 0).all()
    kids = ref[inner].astype(np.int64)
    assert ((kids > 0) & (kids < bvh.node_count)).all()
    # Every non-root node is referenced exactly once: the references form a tree.
    assert np.array_equal(np.sort(kids), np.arange(1, bvh.node_count))
    first = (ref[leaf] & ~np.uint32(LEAF_FLAG)).astype(np.int64)
    count = cnt[leaf].astype(np.int64)
    assert (count <= max_leaf).all(), f"leaf of {count.max()} > {max_leaf}"
    # Leaf ranges tile [0, N) exactly once.
    cover = np.zeros(N + 1, np.int64)
    np.add.at(cover, first[count > 0], 1)
    np.add.at(cover, (first + count)[count > 0], -1)
    assert (np.cumsum(cover)[:N] == 1).all(), "leaf ranges do not cover every primitive exactly once"
    # Leaf boxes hold their primitives; interior boxes hold both boxes of the child node.
    pl, ph = lo[bvh.order], hi[bvh.order]
    leaf_slot = np.repeat(np.arange(leaf.sum()), count)
    pos = np.repeat(first, count) + (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count))
    assert (slo[leaf][leaf_slot] <= pl[pos]).all() and (shi[leaf][leaf_slot] >= ph[pos]).all()
    clo, chi = slo[kids].min(axis=1), shi[kids].max(axis=1)
    assert (slo[inner] <= clo).all() and (shi[inner] >= chi).all(), "a child box sticks out of its parent's slot"
    assert bvh.depth <= 64


def random_tree(n, max_leaf):
    """(lo, hi, bvh) of n random triangles and n // 3 spheres (the seed follows n and max_leaf)."""
    rng = np.random.default_rng(n * 10 + max_leaf)
    lo, hi = primitive_bounds(*random_soup(rng, n), random_spheres(rng, n // 3))
    return lo, hi, build_bvh(lo, hi, max_leaf_size=max_leaf)


@pytest.mark.parametrize("n", [0, 1, 2, 3, 5, 33, 100, 2000])
@pytest.mark.parametrize("max_leaf", [1, 4, 8])
def test_build_invariants_random(n, max_leaf):
    lo, hi, bvh = random_tree(n, max_leaf)
    check_invariants(bvh, lo, hi, max_leaf)


@pytest.mark.parametrize("n_bins", [2, 16, 32])
def test_build_invariants_clustered(n_bins):
    # Clusters of very different sizes, exact duplicates and far outliers exercise uneven binned splits.
    rng = np.random.default_rng(n_bins)
    parts = [random_soup(rng, 500, 1.0, 0.01), random_soup(rng, 300, 1e-4, 1e-5), random_soup(rng, 5, 1e4, 1.0)]
    v = [np.concatenate([p[i] for p in parts] + [np.tile(parts[0][i][:1], (200, 1))]) for i in range(3)]
    lo, hi = primitive_bounds(*v, None)
    bvh = build_bvh(lo, hi, n_bins=n_bins)
    check_invariants(bvh, lo, hi, 4)


def test_identical_pile_terminates_with_bounded_leaves():
    v0, v1, v2 = np.zeros((1000, 3)), np.tile([[1.0, 0, 0]], (1000, 1)), np.tile([[0, 1.0, 0]], (1000, 1))
    lo, hi = primitive_bounds(v0, v1, v2, None)
    bvh = build_bvh(lo, hi, max_leaf_size=4)
    check_invariants(bvh, lo, hi, 4)
    assert bvh.depth <= 12


def test_sah_beats_a_median_split_tree():
    # A sanity check of quality: on clustered input SAH must do better than a leaf-everything tree.
    rng = np.random.default_rng(5)
    lo, hi = primitive_bounds(*random_soup(rng, 3000, 1.0, 0.02), None)
    bvh = build_bvh(lo, hi)
    assert bvh.sah_cost < 0.05 * 3000 and bvh.sah_cost > 1


def test_primitive_packing():
    rng = np.random.default_rng(0)
    v0, v1, v2 = random_soup(rng, 3)
    sp = random_spheres(rng, 2)
    order = np.array([4, 0, 3, 2, 1])
    p = pack_primitives(v0, v1, v2, sp, order).reshape(5, 3, 4)
    ids = p[:, 0, 3].view(np.uint32)
    assert list(ids) == [1 | 0x80000000, 0, 0x80000000, 2, 1]
    assert np.array_equal(p[1, 1, :3], v1[0].astype(np.float32))
    assert np.array_equal(p[3, 2, :3], v2[2].astype(np.float32))
    assert np.allclose(p[0, 0, :3], sp[1, :3]) and np.isclose(p[0, 1, 0], sp[1, 3])
    lo, hi = primitive_bounds(v0, v1, v2, sp)
    assert (lo[3] < sp[0, :3] - sp[0, 3] + 1e-6).all() and (hi[3] >= (sp[0, :3] + sp[0, 3]).astype(np.float32)).all()


def random_leaves(seed):
    """40 triangles and 5 spheres in a random primitive order, cut into leaves of 1..9 primitives: (v0, v1, v2,
    spheres, order, first, count, perm), perm a random order of the leaves (they may come in any order)."""
    rng = np.random.default_rng(seed)
    v0, v1, v2 = random_soup(rng, 40)
    sp = random_spheres(rng, 5)
    order = rng.permutation(45)
    count = np.array([1, 2, 3, 4, 5, 6, 7, 8, 9])
    first = np.concatenate([[0], np.cumsum(count)[:-1]])
    perm = rng.permutation(len(count))
    return v0, v1, v2, sp, order, first, count, perm


def test_leaf_blocks_layout():
    # Word 10 s + r c + l of the device table is row r of lane l of the block of c primitives at s; rows
    # 0..8 the vertices, row 9 the id, exactly the words of the 3-row table, for leaves of 1..9 primitives.
    v0, v1, v2, sp, order, first, count, perm = random_leaves(1)
    words = pack_leaf_blocks(v0, v1, v2, sp, order, first[perm], count[perm]).reshape(-1).view(np.uint32)
    rows = pack_primitives(v0, v1, v2, sp, order).reshape(-1, 3, 4).view(np.uint32)
    want = np.concatenate([rows[:, 0, :3], rows[:, 1, :3], rows[:, 2, :3], rows[:, 0, 3:]], axis=1)
    for f, n in zip(first, count):
        for s in range(f, f + n, 4):
            c = min(4, f + n - s)
            for lane in range(c):
                got = [words[10 * s + r * c + lane] for r in range(10)]
                assert got == list(want[s + lane]), (f, n, s, lane)
    assert len(words) >= 10 * 45 + 3                       # a 4-word load at the last row stays inside
    with pytest.raises(ValueError, match="exactly once"):
        pack_leaf_blocks(v0, v1, v2, sp, order, first, count + 1)


def test_leaf_refs_find_the_vertices():
    # pack_scene's id words: a triangle's leaf reference pos << 4 | lane << 2 | (c - 1) leads back to its own
    # vertices as kernels/shapes/mesh.h mesh_triangle reads them (block at pos - lane, rows of c words);
    # spheres keep their ids.
    v0, v1, v2, sp, order, first, count, perm = random_leaves(2)
    refs = leaf_refs(first[perm], count[perm])
    tri = order < 40
    tri_ref = np.empty(40, np.uint32)
    tri_ref[order[tri]] = refs[tri]
    words = pack_leaf_blocks(v0, v1, v2, sp, order, first[perm], count[perm], tri_ids=tri_ref).reshape(-1)
    bits = words.view(np.uint32)
    for i in range(40):
        ref = int(tri_ref[i])
        pos, lane, c = ref >> 4, (ref >> 2) & 3, (ref & 3) + 1
        assert order[pos] == i
        q = 10 * (pos - lane) + lane
        got = np.array([words[q + r * c] for r in range(9)]).reshape(3, 3)
        want = np.array([v0[i], v1[i], v2[i]], np.float32)
        assert np.array_equal(got, want), i
        assert bits[q + 9 * c] == ref
    spheres = [int(bits[10 * (p - ((r >> 2) & 3)) + ((r >> 2) & 3) + 9 * ((r & 3) + 1)])
               for p, r in enumerate(refs) if not tri[p]]
    assert sorted(spheres) == [j | 0x80000000 for j in range(5)]
    with pytest.raises(ValueError, match="one word per triangle"):
        pack_leaf_blocks(v0, v1, v2, sp, order, first, count, tri_ids=tri_ref[:-1])


# ---------------------------------------------------------------------------------------------- traversal
@pytest.mark.parametrize("n", [1, 2, 100, 5000])
@pytest.mark.parametrize("max_leaf", [1, 4, 8])
def test_triangle_soup(ctx, queue, trace_kernel, n, max_leaf):
    rng = np.random.default_rng(100 + n)
    tris = random_soup(rng, n, size=0.3 if n < 1000 else 0.05)
    o, d, tmin, tmax = rays = random_rays(rng, 2000)
    # Aim half the rays at points on the triangles so that tiny scenes get hits too.
    k = rng.integers(0, n, 1000)
    b = rng.dirichlet([1, 1, 1], 1000)
    target = b[:, :1] * tris[0][k] + b[:, 1:2] * tris[1][k] + b[:, 2:] * tris[2][k]
    d[:1000] = (target - o[:1000]) * rng.uniform(0.2, 5, (1000, 1))
    found, _ = check_trace(ctx, queue, trace_kernel, *tris, None, *rays, max_leaf_size=max_leaf)
    assert found.sum() > 300


def test_soup_with_spheres(ctx, queue, trace_kernel):
    rng = np.random.default_rng(7)
    found, _ = check_trace(ctx, queue, trace_kernel, *random_soup(rng, 300, size=0.1), random_spheres(rng, 60),
                           *random_rays(rng, 3000))
    assert found.sum() > 500


def test_spheres_only_and_rays_from_inside(ctx, queue, trace_kernel):
    rng = np.random.default_rng(8)
    sp = random_spheres(rng, 40)
    o, d, tmin, tmax = random_rays(rng, 2000)
    k = rng.integers(0, 40, 1000)
    o[:1000] = sp[k, :3] + rng.uniform(-0.5, 0.5, (1000, 3)) * sp[k, 3:4]   # strictly inside sphere k
    tmin[:1000] = 0.0
    found, ref = check_trace(ctx, queue, trace_kernel, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), sp,
                             o, d, tmin, tmax)
    assert ref[:1000][np.isinf(tmax[:1000])].all()            # from inside with no tmax, always a hit


def test_axis_aligned_rays_and_triangles(ctx, queue, trace_kernel):
    rng = np.random.default_rng(9)
    v0, v1, v2 = random_soup(rng, 400, size=0.1)
    v1[:100, 0] = v0[:100, 0]                                   # triangles in planes x = const: flat boxes
    v2[:100, 0] = v0[:100, 0]
    v1[100:200, 2] = v2[100:200, 2] = v0[100:200, 2]
    o, d, tmin, tmax = random_rays(rng, 3000, zero_components=True)
    found, _ = check_trace(ctx, queue, trace_kernel, v0, v1, v2, random_spheres(rng, 10), o, d, tmin, tmax)
    assert found.sum() > 300


def test_coplanar_and_duplicate_triangles(ctx, queue, trace_kernel):
    rng = np.random.default_rng(10)
    g = np.linspace(-1, 1, 9)
    x, y = np.meshgrid(g[:-1], g[:-1])
    x, y = x.ravel(), y.ravel()
    h = g[1] - g[0]
    z = np.zeros_like(x)
    a = np.stack([x, y, z], 1)
    b = np.stack([x + h, y, z], 1)
    c = np.stack([x, y + h, z], 1)
    dd = np.stack([x + h, y + h, z], 1)
    v0 = np.concatenate([a, dd, a, a, dd])                      # a grid, then duplicates of part of it
    v1 = np.concatenate([b, c, b, b, c])
    v2 = np.concatenate([c, b, c, c, b])
    big = np.array([[-1, -1, 0.0]]), np.array([[3, -1, 0.0]]), np.array([[-1, 3, 0.0]])  # overlaps the grid
    v0, v1, v2 = (np.concatenate([p, q]) for p, q in zip((v0, v1, v2), big))
    n = 2000
    o = np.stack([rng.uniform(-1.2, 1.2, n), rng.uniform(-1.2, 1.2, n), rng.uniform(0.2, 2, n)], 1)
    o[n // 2:, 2] *= -1
    d = np.stack([rng.normal(0, 0.3, n), rng.normal(0, 0.3, n), -np.sign(o[:, 2]) * rng.uniform(0.5, 2, n)], 1)
    found, ref = check_trace(ctx, queue, trace_kernel, v0, v1, v2, None, o, d, np.zeros(n), np.full(n, np.inf),
                             max_ambiguous=0.1)
    assert ref.mean() > 0.5


def test_icosphere_mesh(ctx, queue, trace_kernel):
    rng = np.random.default_rng(11)
    v0, v1, v2 = icosphere(4)                                   # 5120 triangles
    n = 3000
    o, d, tmin, tmax = random_rays(rng, n, spread=2.0)
    o[: n // 2] *= 0.25                                         # half the rays start inside the closed mesh
    tmin[: n // 4], tmax[: n // 4] = 0.0, np.inf
    found, ref = check_trace(ctx, queue, trace_kernel, v0, v1, v2, None, o, d, tmin, tmax)
    inside_unbounded = slice(0, n // 4)
    assert ref[inside_unbounded].mean() > 0.98


def test_single_primitives_and_empty_scene(ctx, queue, trace_kernel):
    rng = np.random.default_rng(12)
    e = np.zeros((0, 3))
    o, d, tmin, tmax = random_rays(rng, 500, spread=0.5)
    check_trace(ctx, queue, trace_kernel, e, e, e, np.array([[0.1, 0.0, -0.1, 0.7]]), o, d, tmin, tmax)
    tri = (np.array([[-1.0, -1, 0]]), np.array([[1.0, -1, 0.2]]), np.array([[0.0, 1, -0.1]]))
    found, _ = check_trace(ctx, queue, trace_kernel, *tri, None, o, d, tmin, tmax)
    assert found.any()
    found, _ = check_trace(ctx, queue, trace_kernel, e, e, e, None, o, d, tmin, tmax)
    assert not found.any()


def test_rays_on_axes_through_a_box_of_spheres(ctx, queue, trace_kernel):
    # Exactly axis-aligned directions with all other components zero, origins off-centre.
    rng = np.random.default_rng(13)
    sp = random_spheres(rng, 80)
    n = 1200
    o = rng.uniform(-1.5, 1.5, (n, 3))
    d = np.zeros((n, 3))
    d[np.arange(n), rng.integers(0, 3, n)] = rng.choice([-1.0, 1.0, -3.0, 0.25], n)
    found, _ = check_trace(ctx, queue, trace_kernel, *random_soup(rng, 200, size=0.1), sp, o, d,
                           np.zeros(n), np.full(n, np.inf))
    assert found.sum() > 100


# ------------------------------------------------------------------------------ build paths and edge cases
@pytest.mark.parametrize("n", [0, 1, 2, 3, 4])
@pytest.mark.parametrize("max_leaf", [1, 2, 4])
def test_tiny_scenes_build_the_optimal_tree(n, max_leaf):
    # Nodes of <= 4 primitives get their whole subtree from a search over every partition, so for a tiny scene
    # the SAH cost must equal the best over all binary trees (brute force over set partitions below).
    rng = np.random.default_rng(7 * n + max_leaf)
    lo, hi = primitive_bounds(*random_soup(rng, n), None)
    bvh = build_bvh(lo, hi, max_leaf_size=max_leaf)
    check_invariants(bvh, lo, hi, max_leaf)
    if n == 0:
        return

    def area(m):
        idx = [i for i in range(n) if m >> i & 1]
        d = np.maximum(hi[idx].max(0).astype(np.float64) - lo[idx].min(0), 0)
        return d[0] * d[1] + d[1] * d[2] + d[2] * d[0]

    def best(m):
        k = bin(m).count("1")
        c = k * area(m) if k <= max_leaf else np.inf
        low = m & -m
        sub = (m ^ low)
        t = (sub - 1) & sub
        while sub:
            c = min(c, area(m) + best(low | t) + best(m ^ (low | t)))
            if t == 0:
                break
            t = (t - 1) & sub
        return c

    full = (1 << n) - 1
    ref = best(full) / (area(full) if area(full) > 0 else 1.0)
    assert bvh.sah_cost == pytest.approx(ref, rel=1e-5)


def test_build_is_deterministic():
    rng = np.random.default_rng(11)
    lo, hi = primitive_bounds(*random_soup(rng, 20000, 1.0, 0.02), random_spheres(rng, 50))
    a, b = build_bvh(lo, hi, sah_samples=64), build_bvh(lo, hi, sah_samples=64)
    assert np.array_equal(a.nodes.view(np.uint32), b.nodes.view(np.uint32))
    assert np.array_equal(a.order, b.order)


def test_sampled_sah_keeps_quality():
    # Large nodes choose their plane from a strided sample; the tree must stay valid and nearly as good.
    rng = np.random.default_rng(12)
    lo, hi = primitive_bounds(*random_soup(rng, 30000, 1.0, 0.01), None)
    full = build_bvh(lo, hi, sah_samples=10 ** 9)
    for s in (64, 256):
        bvh = build_bvh(lo, hi, sah_samples=s)
        check_invariants(bvh, lo, hi, 4)
        assert bvh.sah_cost < 1.05 * full.sah_cost


@pytest.mark.parametrize("max_leaf", [1, 4])
def test_coincident_centroids_with_different_boxes(max_leaf):
    # Nested boxes around one centre (no plane separates any two centroids) plus a flat (z = 0) sheet.
    k = np.arange(1, 301, dtype=np.float64)[:, None]
    lo = np.concatenate([-k * [1, 1, 1], np.stack([np.arange(500.0), np.zeros(500), np.zeros(500)], 1)])
    hi = np.concatenate([k * [1, 1, 1], np.stack([np.arange(500.0) + 0.5, np.ones(500), np.zeros(500)], 1)])
    bvh = build_bvh(lo, hi, max_leaf_size=max_leaf)
    check_invariants(bvh, lo.astype(np.float32), hi.astype(np.float32), max_leaf)


@pytest.mark.parametrize("n", [5, 17, 40])
def test_piles_of_identical_boxes(n):
    lo = np.zeros((n, 3))
    hi = np.ones((n, 3))
    for max_leaf in (1, 3, 4):
        bvh = build_bvh(lo, hi, max_leaf_size=max_leaf)
        check_invariants(bvh, lo, hi, max_leaf)


# ------------------------------------------------------------------ device build (kernels/bvh_build.cl)
# method="device" builds the top levels on the host until nodes hold <= subtree_size primitives, then every
# such node's subtree in one OpenCL work-item; a small subtree_size exercises both halves and the splicing.
def device_build(lo, hi, subtree_size, **kw):
    return build_bvh(lo, hi, method="device", subtree_size=subtree_size, **kw)


@pytest.mark.parametrize("n", [1, 2, 3, 5, 33, 100, 2000])
@pytest.mark.parametrize("max_leaf", [1, 4, 8])
@pytest.mark.parametrize("subtree", [1, 16, 10 ** 9], ids=["all-host-levels", "mixed", "all-device"])
def test_device_build_invariants(cl_env, n, max_leaf, subtree):
    rng = np.random.default_rng(n * 10 + max_leaf)
    lo, hi = primitive_bounds(*random_soup(rng, n), random_spheres(rng, n // 3))
    bvh = device_build(lo, hi, subtree, max_leaf_size=max_leaf)
    check_invariants(bvh, lo, hi, max_leaf)
    assert bvh.max_leaf_prims <= max_leaf and bvh.leaf_count >= len(lo) / max_leaf


@pytest.mark.parametrize("n", [1, 2, 3, 4])
@pytest.mark.parametrize("max_leaf", [1, 2, 4])
def test_device_tiny_subtrees_are_optimal(cl_env, n, max_leaf):
    # The kernel's subset programme must find the same optimum as the host's (itself checked by brute force).
    rng = np.random.default_rng(7 * n + max_leaf)
    lo, hi = primitive_bounds(*random_soup(rng, n), None)
    host = build_bvh(lo, hi, max_leaf_size=max_leaf, method="host")
    dev = device_build(lo, hi, 10 ** 9, max_leaf_size=max_leaf)
    check_invariants(dev, lo, hi, max_leaf)
    assert dev.sah_cost == pytest.approx(host.sah_cost, rel=1e-5)


def test_device_build_sah_no_worse_than_host(cl_env):
    # "Equal or better": all primitives binned in 32 bins below the hand-over, against sampled 16-bin SAH.
    rng = np.random.default_rng(21)
    parts = [random_soup(rng, 20000, 1.0, 0.01), random_soup(rng, 5000, 0.05, 0.002)]
    v = [np.concatenate([p[i] for p in parts]) for i in range(3)]
    lo, hi = primitive_bounds(*v, random_spheres(rng, 300))
    host = build_bvh(lo, hi, method="host")
    for subtree in (4096, 10 ** 9):
        dev = device_build(lo, hi, subtree)
        check_invariants(dev, lo, hi, 4)
        assert dev.sah_cost <= host.sah_cost * 1.001, (subtree, dev.sah_cost, host.sah_cost)
        assert dev.depth <= 64


def test_device_build_is_deterministic(cl_env):
    rng = np.random.default_rng(11)
    lo, hi = primitive_bounds(*random_soup(rng, 20000, 1.0, 0.02), random_spheres(rng, 50))
    a, b = device_build(lo, hi, 1000), device_build(lo, hi, 1000)
    assert np.array_equal(a.nodes.view(np.uint32), b.nodes.view(np.uint32))
    assert np.array_equal(a.order, b.order)


@pytest.mark.parametrize("subtree", [8, 10 ** 9])
def test_device_identical_pile(cl_env, subtree):
    v0, v1, v2 = np.zeros((1000, 3)), np.tile([[1.0, 0, 0]], (1000, 1)), np.tile([[0, 1.0, 0]], (1000, 1))
    lo, hi = primitive_bounds(v0, v1, v2, None)
    for max_leaf in (1, 4):
        bvh = device_build(lo, hi, subtree, max_leaf_size=max_leaf)
        check_invariants(bvh, lo, hi, max_leaf)
        assert bvh.depth <= 12


@pytest.mark.parametrize("max_leaf", [1, 4])
def test_device_flat_and_coincident(cl_env, max_leaf):
    # Nested boxes around one centre (no plane separates their centroids) plus a flat (z = 0) sheet, and a
    # flat scene alone: zero-area boxes, zero extent on one axis.
    k = np.arange(1, 301, dtype=np.float64)[:, None]
    lo = np.concatenate([-k * [1, 1, 1], np.stack([np.arange(500.0), np.zeros(500), np.zeros(500)], 1)])
    hi = np.concatenate([k * [1, 1, 1], np.stack([np.arange(500.0) + 0.5, np.ones(500), np.zeros(500)], 1)])
    for l_, h_ in ((lo, hi), (lo[300:], hi[300:])):
        for subtree in (16, 10 ** 9):
            bvh = device_build(l_, h_, subtree, max_leaf_size=max_leaf)
            check_invariants(bvh, l_.astype(np.float32), h_.astype(np.float32), max_leaf)


def test_device_build_one_primitive_and_empty(cl_env):
    lo, hi = np.zeros((1, 3)), np.ones((1, 3))
    bvh = device_build(lo, hi, 10 ** 9)
    check_invariants(bvh, lo, hi, 4)
    assert bvh.node_count == 1 and bvh.sah_cost == 1.0 and bvh.leaf_count == 1
    empty = device_build(np.zeros((0, 3)), np.zeros((0, 3)), 10 ** 9)
    assert empty.node_count == 1 and len(empty.order) == 0


def test_device_build_traces_correctly(ctx, queue):
    rng = np.random.default_rng(33)
    v0, v1, v2 = random_soup(rng, 3000, 1.0, 0.1)
    sph = random_spheres(rng, 40)
    tracer = make_tracer(ctx, 2)
    check_trace(ctx, queue, tracer, v0, v1, v2, sph, *random_rays(rng, 3000), method="device", subtree_size=64)


def test_auto_falls_back_to_the_host_without_a_device(monkeypatch):
    from clrender.accel import bvh as bvh_mod
    from clrender.accel import bvh_device

    rng = np.random.default_rng(3)
    lo, hi = primitive_bounds(*random_soup(rng, 3000), None)
    monkeypatch.setattr(bvh_mod, "DEVICE_MIN", 1)
    monkeypatch.setattr(bvh_device, "device_context", lambda spec=None: None)
    a, b = build_bvh(lo, hi, method="auto"), build_bvh(lo, hi, method="host")
    assert np.array_equal(a.nodes.view(np.uint32), b.nodes.view(np.uint32))
    with pytest.raises(Exception, match="no OpenCL device"):
        build_bvh(lo, hi, method="device")
    with pytest.raises(ValueError, match="method"):
        build_bvh(lo, hi, method="gpu")


def test_auto_falls_back_to_the_host_when_the_device_build_fails(monkeypatch, cl_env):
    from clrender.accel import bvh as bvh_mod
    from clrender.accel import bvh_device
    from clrender.errors import DeviceError

    def broken(*a, **k):
        raise DeviceError("OpenCL program failed to build")

    rng = np.random.default_rng(4)
    lo, hi = primitive_bounds(*random_soup(rng, 3000), None)
    monkeypatch.setattr(bvh_mod, "DEVICE_MIN", 1)
    monkeypatch.setattr(bvh_device, "build_subtrees", broken)
    a, b = build_bvh(lo, hi, method="auto"), build_bvh(lo, hi, method="host")
    assert np.array_equal(a.nodes.view(np.uint32), b.nodes.view(np.uint32))
    with pytest.raises(DeviceError):
        build_bvh(lo, hi, method="device")


_OCLGRIND_BUILD = """
import sys
import numpy as np
sys.path.insert(0, sys.argv[1])
from test_bvh import check_invariants, random_soup, random_spheres
from clrender.accel.bvh import build_bvh
from clrender.accel.primitives import primitive_bounds
rng = np.random.default_rng(5)
v = [np.concatenate([a, np.tile(a[:1], (40, 1))]) for a in random_soup(rng, 300, 1.0, 0.05)]   # + a pile
lo, hi = primitive_bounds(*v, random_spheres(rng, 20))
for subtree, max_leaf in ((16, 4), (10 ** 9, 1)):
    bvh = build_bvh(lo, hi, method="device", subtree_size=subtree, max_leaf_size=max_leaf, device="Oclgrind")
    check_invariants(bvh, lo, hi, max_leaf)
print("built")
"""


def test_device_build_is_clean_under_oclgrind(tmp_path):
    # The kernel under a second OpenCL implementation with out-of-bounds and data-race checks on.
    from test_oclgrind import _oclgrind_present, _run_under_oclgrind

    if not _oclgrind_present():
        pytest.skip("Oclgrind is not installed (pip install -e '.[test]')")
    proc, report = _run_under_oclgrind(tmp_path, [str(Path(__file__).parent)], _OCLGRIND_BUILD)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "built" in proc.stdout
    assert report == "", report[:4000]
