"""The 4-wide BVH: collapse invariants on the host (clrender/accel/bvh4.py), kernels/bvh4.h traversal against
the float64 brute force of test_bvh.py, and renders with the 2-wide and the 4-wide tree agreeing."""
import numpy as np
import pytest

from clrender.accel.bvh import LEAF_FLAG, build_bvh
from clrender.accel.bvh4 import (EMPTY_HI, EMPTY_LO, NODE_ROWS, Bvh4Unsupported, collapse_bvh4, decode_leaf)
from clrender.accel.primitives import primitive_bounds
from test_bvh import (TRACE_SRC, build_scene, compare_with_reference, device_trace, icosphere, random_rays,
                      random_soup, random_spheres)


# -------------------------------------------------------------------------------------- host invariants
def check_invariants4(b4, lo, hi, order, max_leaf):
    N = len(lo)
    nodes = b4.nodes.reshape(-1, NODE_ROWS, 4)
    K = b4.node_count
    assert len(nodes) == K and K >= 1
    blo = np.stack([nodes[:, 0], nodes[:, 2], nodes[:, 4]], -1)          # (K, 4 children, 3)
    bhi = np.stack([nodes[:, 1], nodes[:, 3], nodes[:, 5]], -1)
    ref = nodes[:, 6].view(np.uint32)
    empty = (blo == EMPTY_LO).all(-1) & (bhi == EMPTY_HI).all(-1)
    valid = ~empty
    # Valid children come first; every node but a small scene's root has at least two.
    assert (np.sort(~valid, axis=1, kind="stable") == ~valid).all()
    nch = valid.sum(1)
    assert (nch[1:] >= 2).all()
    assert (blo[valid] <= bhi[valid]).all()
    leaf = valid & ((ref & np.uint32(LEAF_FLAG)) != 0)
    inner = valid & ~leaf
    kids = ref[inner].astype(np.int64)
    # Interior references form a tree rooted at node 0, children after their parent.
    assert np.array_equal(np.sort(kids), np.arange(1, K))
    parent = np.repeat(np.arange(K), inner.sum(1))
    assert (kids > parent).all()
    # Leaf ranges tile [0, N) exactly once and stay within max_leaf.
    first, count = decode_leaf(ref[leaf])
    assert (count >= 1).all() and (count <= max_leaf).all()
    cover = np.zeros(N + 1, np.int64)
    np.add.at(cover, first, 1)
    np.add.at(cover, first + count, -1)
    assert (np.cumsum(cover)[:N] == 1).all(), "leaf ranges do not cover every primitive exactly once"
    # Leaf boxes hold their primitives; interior boxes hold every child box of the node they point to.
    pl, ph = lo[order], hi[order]
    slot = np.repeat(np.arange(leaf.sum()), count)
    pos = np.repeat(first, count) + (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count))
    assert (blo[leaf][slot] <= pl[pos]).all() and (bhi[leaf][slot] >= ph[pos]).all()
    big = np.where(valid[..., None], blo, np.inf).min(1), np.where(valid[..., None], bhi, -np.inf).max(1)
    assert (blo[inner] <= big[0][kids]).all() and (bhi[inner] >= big[1][kids]).all()
    # stack_need: along every root-to-node path, pending siblings plus this node's children.
    acc = np.zeros(K, np.int64)
    for k in range(K):                                       # parents come before children
        acc[ref[k][inner[k]].astype(np.int64)] = acc[k] + nch[k] - 1
    assert b4.stack_need == int((acc + nch).max())
    return nch


@pytest.mark.parametrize("n", [0, 1, 2, 3, 5, 33, 100, 2000])
@pytest.mark.parametrize("max_leaf", [1, 4, 8])
def test_collapse_invariants_random(n, max_leaf):
    rng = np.random.default_rng(n * 10 + max_leaf)
    lo, hi = primitive_bounds(*random_soup(rng, n), random_spheres(rng, n // 3))
    bvh = build_bvh(lo, hi, max_leaf_size=max_leaf)
    b4 = collapse_bvh4(bvh)
    check_invariants4(b4, lo, hi, bvh.order, max_leaf)
    assert b4.node_count <= bvh.node_count and b4.depth <= max(bvh.depth, 1)


def test_collapse_fills_nodes():
    rng = np.random.default_rng(1)
    lo, hi = primitive_bounds(*icosphere(4), None)
    bvh = build_bvh(lo, hi)
    b4 = collapse_bvh4(bvh)
    nch = check_invariants4(b4, lo, hi, bvh.order, 4)
    assert nch.mean() > 3.0                                   # the greedy collapse fills most slots
    assert b4.node_count < 0.6 * bvh.node_count
    assert b4.leaf_count == bvh.leaf_count


def test_collapse_rejects_what_the_kernel_cannot_take():
    v0, v1, v2 = np.zeros((20, 3)), np.tile([[1.0, 0, 0]], (20, 1)), np.tile([[0, 1.0, 0]], (20, 1))
    lo, hi = primitive_bounds(v0, v1, v2, None)
    with pytest.raises(Bvh4Unsupported):                      # one leaf of 20 > 16 primitives
        collapse_bvh4(build_bvh(lo, hi, max_leaf_size=20))
    rng = np.random.default_rng(2)
    lo, hi = primitive_bounds(*random_soup(rng, 2000), None)
    with pytest.raises(Bvh4Unsupported):
        collapse_bvh4(build_bvh(lo, hi), stack_size=4)


# ---------------------------------------------------------------------------------------------- traversal
@pytest.fixture(scope="module")
def trace4(ctx):
    import pyopencl as cl

    from clrender.device.program import build_program

    prg = build_program(ctx, TRACE_SRC.replace('#include "bvh.h"', '#include "bvh4.h"'), with_types=False)
    return cl.Kernel(prg, "trace")


class _Nodes:
    def __init__(self, nodes):
        self.nodes = nodes


def check_trace4(ctx, queue, kernel, v0, v1, v2, spheres, o, d, tmin, tmax, max_ambiguous=0.02, **kw):
    bvh, prims = build_scene(v0, v1, v2, spheres, **kw)
    b4 = collapse_bvh4(bvh)
    check_invariants4(b4, *primitive_bounds(v0, v1, v2, spheres), bvh.order, kw.get("max_leaf_size", 4))
    out, prim, any_ = device_trace(ctx, queue, kernel, _Nodes(b4.nodes), prims, o, d, tmin, tmax)
    return compare_with_reference(out, prim, any_, v0, v1, v2, spheres, o, d, tmin, tmax, max_ambiguous)


@pytest.mark.parametrize("n", [1, 2, 100, 5000])
@pytest.mark.parametrize("max_leaf", [1, 4, 8])
def test_triangle_soup4(ctx, queue, trace4, n, max_leaf):
    rng = np.random.default_rng(200 + n)
    tris = random_soup(rng, n, size=0.3 if n < 1000 else 0.05)
    o, d, tmin, tmax = rays = random_rays(rng, 2000)
    k = rng.integers(0, n, 1000)
    b = rng.dirichlet([1, 1, 1], 1000)
    target = b[:, :1] * tris[0][k] + b[:, 1:2] * tris[1][k] + b[:, 2:] * tris[2][k]
    d[:1000] = (target - o[:1000]) * rng.uniform(0.2, 5, (1000, 1))
    found, _ = check_trace4(ctx, queue, trace4, *tris, None, *rays, max_leaf_size=max_leaf)
    assert found.sum() > 300


def test_soup_with_spheres4(ctx, queue, trace4):
    rng = np.random.default_rng(17)
    found, _ = check_trace4(ctx, queue, trace4, *random_soup(rng, 300, size=0.1), random_spheres(rng, 60),
                            *random_rays(rng, 3000))
    assert found.sum() > 500


def test_spheres_from_inside4(ctx, queue, trace4):
    rng = np.random.default_rng(18)
    sp = random_spheres(rng, 40)
    o, d, tmin, tmax = random_rays(rng, 2000)
    k = rng.integers(0, 40, 1000)
    o[:1000] = sp[k, :3] + rng.uniform(-0.5, 0.5, (1000, 3)) * sp[k, 3:4]
    tmin[:1000] = 0.0
    e = np.zeros((0, 3))
    check_trace4(ctx, queue, trace4, e, e, e, sp, o, d, tmin, tmax)


def test_axis_aligned_rays_and_flat_boxes4(ctx, queue, trace4):
    # Zero direction components (+0 and -0) pick the near plane by sign; flat boxes have lo == hi.
    rng = np.random.default_rng(19)
    v0, v1, v2 = random_soup(rng, 400, size=0.1)
    v1[:100, 0] = v2[:100, 0] = v0[:100, 0]
    v1[100:200, 2] = v2[100:200, 2] = v0[100:200, 2]
    o, d, tmin, tmax = random_rays(rng, 3000, zero_components=True)
    found, _ = check_trace4(ctx, queue, trace4, v0, v1, v2, random_spheres(rng, 10), o, d, tmin, tmax)
    assert found.sum() > 300
    n = 1200
    o = rng.uniform(-1.5, 1.5, (n, 3))
    d = np.zeros((n, 3))
    d[np.arange(n), rng.integers(0, 3, n)] = rng.choice([-1.0, 1.0, -3.0, 0.25], n)
    check_trace4(ctx, queue, trace4, *random_soup(rng, 200, size=0.1), random_spheres(rng, 80), o, d,
                 np.zeros(n), np.full(n, np.inf))


def test_icosphere_mesh4(ctx, queue, trace4):
    rng = np.random.default_rng(21)
    n = 3000
    o, d, tmin, tmax = random_rays(rng, n, spread=2.0)
    o[: n // 2] *= 0.25
    tmin[: n // 4], tmax[: n // 4] = 0.0, np.inf
    _, ref = check_trace4(ctx, queue, trace4, *icosphere(4), None, o, d, tmin, tmax)
    assert ref[: n // 4].mean() > 0.98


def test_tiny_and_empty_scenes4(ctx, queue, trace4):
    rng = np.random.default_rng(22)
    e = np.zeros((0, 3))
    o, d, tmin, tmax = random_rays(rng, 500, spread=0.5)
    check_trace4(ctx, queue, trace4, e, e, e, np.array([[0.1, 0.0, -0.1, 0.7]]), o, d, tmin, tmax)
    tri = (np.array([[-1.0, -1, 0]]), np.array([[1.0, -1, 0.2]]), np.array([[0.0, 1, -0.1]]))
    found, _ = check_trace4(ctx, queue, trace4, *tri, None, o, d, tmin, tmax)
    assert found.any()
    found, _ = check_trace4(ctx, queue, trace4, e, e, e, None, o, d, tmin, tmax)
    assert not found.any()


# ------------------------------------------------------------------------------------------------ renders
def test_renders_agree_for_both_widths():
    """Same seed, same samples: the 2-wide and 4-wide trees find the same hits (up to exact ties)."""
    from pathlib import Path

    from clrender import load_scene
    from clrender.pack import pack_scene
    from clrender.renderer import Renderer

    path = Path(__file__).resolve().parents[1] / "scenes" / "cornell" / "cornell_path_mis.xml"
    scene = load_scene(path)
    films = {}
    for w in (2, 4):
        bufs = pack_scene(scene, bvh_width=w)
        assert bufs.bvh_width == w and bufs.stats["bvh_width"] == w
        films[w] = Renderer(scene, buffers=bufs, count_rays=True).render(spp=4, seed=3)
    a, b = films[2], films[4]
    assert a.stats.rays == b.stats.rays or abs(a.stats.rays_total - b.stats.rays_total) < 1e-4 * a.stats.rays_total
    ia, ib = np.asarray(a.image), np.asarray(b.image)
    same = np.all(ia == ib, axis=-1)
    assert same.mean() > 0.999, f"only {same.mean():.4f} of the pixels are identical"
