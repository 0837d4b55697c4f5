"""Watertight triangles: rays aimed exactly at the shared edges and vertices of closed meshes never slip
through, in both BVH widths; and the furnace, whose value only holds if no BSDF-sampled ray escapes.

A closed surface seen along any line is entered and left; float rounding in a per-triangle test (Möller-
Trumbore) can put a point on a shared edge outside *both* triangles, so a ray through it misses the mesh. The
traversal kernels use edge functions computed the same way on both sides of an edge (Woop, Benthin and Wald
2013), which cannot do that. With the old Möller-Trumbore kernel (commit 156b891) the edge/vertex test below
lost 44 of 85,344 rays per width on the cube and the UV sphere.
"""
import numpy as np
import pytest

from test_bvh import _Nodes, build_scene, device_trace, make_tracer


@pytest.fixture(scope="module", params=[2, 4], ids=["bvh2", "bvh4"])
def tracer(ctx, request):
    return make_tracer(ctx, request.param)


# ------------------------------------------------------------------------------------------------ meshes
def subdivided_cube(n, lo=(-1.0, -1.0, -1.0), hi=(1.0, 1.0, 1.0)):
    """A closed box, each face an n x n grid of quads split into two triangles: (F, 3) vertex indices into
    (V, 3) positions, every grid vertex stored once so neighbouring faces share it exactly."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    s = np.linspace(0.0, 1.0, n + 1)
    index, verts, tris = {}, [], []

    def vid(g):                      # g: integer grid coordinates in [0, n]^3 on the box surface
        if g not in index:
            index[g] = len(verts)
            verts.append(lo + (hi - lo) * s[list(g)])
        return index[g]

    for axis in range(3):
        a, b = (axis + 1) % 3, (axis + 2) % 3
        for side in (0, n):
            for i in range(n):
                for j in range(n):
                    q = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        g = [0, 0, 0]
                        g[axis], g[a], g[b] = side, i + di, j + dj
                        q.append(vid(tuple(g)))
                    # Alternate the diagonal so vertices of valence 4, 6 and 8 all occur.
                    if (i + j) % 2:
                        tris += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
                    else:
                        tris += [(q[0], q[1], q[3]), (q[1], q[2], q[3])]
    return np.array(verts), np.array(tris)


def uv_sphere(rings, segments, radius=1.0, center=(0.0, 0.0, 0.0)):
    """A closed UV sphere: triangle fans at the poles (vertices of valence `segments`), quads split in two."""
    th = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    ph = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    ring = np.stack([np.sin(th)[:, None] * np.cos(ph), np.sin(th)[:, None] * np.sin(ph),
                     np.cos(th)[:, None] * np.ones_like(ph)], -1).reshape(-1, 3)
    verts = np.concatenate([[[0, 0, 1.0]], ring, [[0, 0, -1.0]]]) * radius + np.asarray(center)
    south = len(verts) - 1
    r = lambda i, j: 1 + i * segments + j % segments  # noqa: E731
    tris = [(0, r(0, j), r(0, j + 1)) for j in range(segments)]
    for i in range(rings - 2):
        for j in range(segments):
            tris += [(r(i, j), r(i + 1, j), r(i + 1, j + 1)), (r(i, j), r(i + 1, j + 1), r(i, j + 1))]
    tris += [(south, r(rings - 2, j + 1), r(rings - 2, j)) for j in range(segments)]
    return verts, np.array(tris)


def edges(tris):
    e = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    u, count = np.unique(e, axis=0, return_counts=True)
    assert (count == 2).all(), "the mesh is not closed"
    return u


# Off-origin placements with "unround" coordinates, so the float32 vertices are not small dyadic numbers.
MESHES = {
    "cube": lambda: subdivided_cube(6, lo=(-0.73, -1.31, 0.29), hi=(1.17, 0.41, 2.03)),
    "uvsphere": lambda: uv_sphere(12, 24, radius=0.9, center=(0.37, -0.21, 1.13)),
    "far_cube": lambda: subdivided_cube(4, lo=(101.3, -47.9, 12.7), hi=(103.1, -46.3, 14.9)),
}


def aimed_rays(verts, tris, rng, n_edge=12):
    """Rays through float32 points on every shared edge and through every vertex of a convex closed mesh, half
    from inside, half from outside. Returns origins, directions (the aimed-at point is at t = 1) and which
    rays start inside.

    Inside origins fill the inscribed ball almost to the surface, so some rays graze the faces they hit. An
    outside origin lies beyond the target on the line from an inside point q, so the ray goes on to q: in
    exact arithmetic it must cross the surface, at the target (a ray aimed at a target merely *near* a convex
    edge, from any direction, could rightly pass outside it)."""
    v32 = verts.astype(np.float32)
    e = edges(tris)
    s = rng.uniform(0.0, 1.0, (len(e), n_edge, 1))
    a, b = v32[e[:, 0]].astype(np.float64)[:, None], v32[e[:, 1]].astype(np.float64)[:, None]
    targets = np.concatenate([(a + s * (b - a)).reshape(-1, 3), np.repeat(v32, 6, axis=0)]).astype(np.float32)
    targets = targets.astype(np.float64)
    centre = verts.mean(axis=0)
    t = verts[tris]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    inradius = np.min(np.abs(np.sum(n * (t[:, 0] - centre), 1)) / np.linalg.norm(n, axis=1))
    m = len(targets)
    g = rng.normal(size=(m, 3))
    q = centre + g / np.linalg.norm(g, axis=1, keepdims=True) * inradius * rng.uniform(0, 0.999, (m, 1)) ** (1 / 3)
    inside = np.arange(m) % 2 == 0
    o = np.where(inside[:, None], q, targets + (targets - q) * rng.uniform(0.05, 2.0, (m, 1))).astype(np.float32)
    return o, (targets - o.astype(np.float64)).astype(np.float32), inside


@pytest.mark.parametrize("mesh", sorted(MESHES))
def test_rays_at_shared_edges_and_vertices_never_miss(ctx, queue, tracer, mesh):
    verts, tris = MESHES[mesh]()
    rng = np.random.default_rng(sorted(MESHES).index(mesh))
    v0, v1, v2 = (verts[tris[:, i]] for i in range(3))
    bvh, prims = build_scene(v0, v1, v2, None)
    tree = bvh
    if tracer.width == 4:
        from clrender.accel.bvh4 import collapse_bvh4

        tree = _Nodes(collapse_bvh4(bvh).nodes)
    o, d, inside = aimed_rays(verts, tris, rng)
    n = len(o)
    tmin, tmax = np.zeros(n), np.full(n, np.inf)
    out, prim, any_ = device_trace(ctx, queue, tracer.kernel, tree, prims, o, d, tmin, tmax)
    found = out[:, 3] > 0
    missed = ~found | (any_ == 0)
    assert not missed.any(), (f"{missed.sum()} of {n} rays aimed at edges/vertices slipped through "
                              f"({(missed & inside).sum()} from inside), e.g. {np.nonzero(missed)[0][:5]}")
    # The mesh is convex, so the aimed-at point is the first hit: t = 1 up to rounding.
    assert np.allclose(out[:, 0], 1.0, atol=1e-4), np.abs(out[:, 0] - 1).max()
    # The hit triangle contains the target: its barycentrics are in [0, 1] (to float precision).
    u, v = out[:, 1], out[:, 2]
    assert (u >= -1e-5).all() and (v >= -1e-5).all() and (u + v <= 1 + 1e-5).all()


def test_open_mesh_is_still_missed_beside_its_border(ctx, queue, tracer):
    """Counting an edge function of exactly 0 as inside must not grow triangles: rays passing 1-3 float32 ulps
    outside an open mesh's border miss it."""
    verts, tris = subdivided_cube(3)
    top = tris[verts[tris].mean(axis=1)[:, 2] > 0.999]       # only the face z = 1: an open square, x in [-1, 1]
    v0, v1, v2 = (verts[top[:, i]] for i in range(3))
    bvh, prims = build_scene(v0, v1, v2, None)
    tree = bvh
    if tracer.width == 4:
        from clrender.accel.bvh4 import collapse_bvh4

        tree = _Nodes(collapse_bvh4(bvh).nodes)
    rng = np.random.default_rng(3)
    m = 2000
    x = np.full(m, 1.0, np.float32)
    for i, k in enumerate(rng.integers(1, 4, m)):
        for _ in range(k):
            x[i] = np.nextafter(x[i], np.float32(2))
    o = np.stack([x, rng.uniform(-1, 1, m).astype(np.float32), np.full(m, 3.0, np.float32)], 1)
    d = np.tile(np.float32([0, 0, -1]), (m, 1))             # straight down, beside the border x = 1
    out, _, any_ = device_trace(ctx, queue, tracer.kernel, tree, prims, o, d, np.zeros(m), np.full(m, np.inf))
    assert not (out[:, 3] > 0).any() and not any_.any()
    # ... and the same rays one ulp inside the border hit.
    o[:, 0] = np.nextafter(np.float32(1.0), np.float32(0))
    out, _, any_ = device_trace(ctx, queue, tracer.kernel, tree, prims, o, d, np.zeros(m), np.full(m, np.inf))
    assert (out[:, 3] > 0).all() and any_.all()
