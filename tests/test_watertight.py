"""Watertight triangles and robust ray offsets: rays aimed exactly at the shared edges and vertices of closed
meshes never slip through, rays spawned from a surface neither re-hit it nor step past a neighbouring wall, in
both BVH widths; and the furnace, whose value only holds if no BSDF-sampled ray escapes.

A closed surface seen along any line is entered and left; float rounding in a per-triangle test (Möller-
Trumbore) can put a point on a shared edge outside *both* triangles, so a ray through it misses the mesh. The
traversal kernels use edge functions computed the same way on both sides of an edge (Woop, Benthin and Wald
2013), which cannot do that. Spawned rays used to skip everything within tmin = ray_eps(p) of p, including
the wall next to a point near a concave edge; they now start off the surface (kernels/scene.h, spawn_origin).

Measured on the code before this change (commit 156b891), in both widths: the edge/vertex rays lost 1006 of
9084 (cube), 338 of 4044 (far cube) and 845 of 11100 (UV sphere), and rays 1 ulp inside an open mesh's border
missed; 496, 711 and 2750 of ~15000 inward spawned rays escaped; the cube furnace gave 1.799976 (z = -5.5,
30 pixels lost a sample). With the normal offset but without moving the spawn point off the triangle's edges,
43 and 131 inward rays still escaped (cube, far cube).
"""
import numpy as np
import pyopencl as cl
import pytest

import analytic_scenes as A
from clrender.device.program import build_program
from clrender.loader import load_scene
from clrender.pack import pack_scene
from clrender.renderer import Renderer
from clrender.testing.stats import compare_mean_to_value
from test_bvh import build_scene, device_trace, make_tracer, wide_nodes

LOCAL = 64


@pytest.fixture(scope="module", params=[2, 4, 8], ids=["bvh2", "bvh4", "bvh8"])
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
    tree = wide_nodes(bvh, tracer.width)
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
    tree = wide_nodes(bvh, tracer.width)
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


# ------------------------------------------------------------------------------------------ spawned rays
SPAWN_SRC = r"""
#include "scene.h"
/* A ray from org along dir finds a surface point; a ray spawned there along frame_dir (z along the normal that
   faces org) is traced again. out0 = (hit point, tri id), out1 = (spawned ray's hit point, tri id or ~0),
   out2 = (spawned direction, any-hit of the same spawned ray). */
__kernel void spawn(SCENE_ARGS, uint n, __global const float4* org, __global const float4* dir,
                    __global const float4* frame_dir, __global float4* out0, __global float4* out1,
                    __global float4* out2) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    Ray r = spawn_ray(vxyz(org[i]), vxyz(dir[i]));
    Intersection its;
    if (!scene_intersect(&sd, &r, &its)) { out0[i] = (float4)(0.0f, 0.0f, 0.0f, as_float(NONE)); return; }
    Frame f = frame_from_normal(dot3(its.ng, r.d) < 0.0f ? its.ng : vneg(its.ng));
    vec3 d = to_world(&f, vxyz(frame_dir[i]));
    Ray s = spawn_ray_from(&its, d);
    Intersection h;
    bool hit = scene_intersect(&sd, &s, &h);
    bool occ = scene_occluded(&sd, s.o, d, s.tmin, s.tmax);
    out0[i] = vf4(its.p, as_float(its.tri));
    out1[i] = hit ? vf4(h.p, as_float(h.tri)) : (float4)(0.0f, 0.0f, 0.0f, as_float(NONE));
    out2[i] = vf4(d, occ ? 1.0f : 0.0f);
}
"""


@pytest.fixture(scope="module", params=[2, 4, 8], ids=["bvh2", "bvh4", "bvh8"])
def spawn_kernel(ctx, request):
    """The spawn kernel built for one BVH width (scene.h picks the traversal by BVH_WIDTH), and that width."""
    prg = build_program(ctx, SPAWN_SRC, defines={"BVH_WIDTH": request.param})
    return cl.Kernel(prg, "spawn"), request.param


def mesh_scene(tmp_path, verts, tris, name="mesh", body=""):
    """A scene file holding one OBJ mesh (triangles as given) and a small camera."""
    obj = tmp_path / f"{name}.obj"
    obj.write_text("".join(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in verts)
                   + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in tris))
    xml = tmp_path / f"{name}.xml"
    xml.write_text(f'<scene><integrator type="normals"/>{A.camera()}<mesh type="obj"><string name="filename" '
                   f'value="{obj.name}"/>{body}</mesh></scene>')
    return xml


def run_rays(ctx, queue, kernel, buffers, *inputs):
    """Run a kernel of (SCENE_ARGS, uint n, the inputs as float4 xyz, three float4 outputs) over n rays; the outputs."""
    n = len(inputs[0])
    g = max(LOCAL, -(-n // LOCAL) * LOCAL)
    ro = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
    scene = [cl.Buffer(ctx, ro, hostbuf=np.ascontiguousarray(a)) for a in buffers.scene_arrays()]

    def f4(a):
        b = np.zeros((g, 4), np.float32)
        b[:n, :3] = a
        return cl.Buffer(ctx, ro, hostbuf=b)

    outs = [cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, g * 16) for _ in range(3)]
    kernel(queue, (g,), (LOCAL,), *scene, np.uint32(n), *(f4(a) for a in inputs), *outs)
    res = []
    for b in outs:
        a = np.empty((g, 4), np.float32)
        cl.enqueue_copy(queue, a, b)
        res.append(a[:n])
    return res


def grazing_directions(rng, n):
    """Unit directions about +z with cos(theta) spread log-uniformly over [1e-5, 1]: mostly grazing."""
    c = 10.0 ** rng.uniform(-5, 0, n)
    phi = rng.uniform(0, 2 * np.pi, n)
    s = np.sqrt(1 - c * c)
    return np.stack([s * np.cos(phi), s * np.sin(phi), c], 1)


@pytest.mark.parametrize("mesh", sorted(MESHES))
def test_spawned_rays_neither_rehit_nor_tunnel(tmp_path, ctx, queue, spawn_kernel, mesh):
    """From points on a convex closed mesh, many of them within 1e-7..1e-1 of an edge, rays spawned inward
    (grazing ones included) must hit another face of the mesh, never their own plane, and rays spawned
    outward must escape. An offset along the ray (tmin) fails the first at concave edges: the wall next
    to the point is nearer than tmin."""
    kernel, width = spawn_kernel
    verts, tris = MESHES[mesh]()
    rng = np.random.default_rng(10 + sorted(MESHES).index(mesh))
    bufs = pack_scene(load_scene(mesh_scene(tmp_path, verts, tris)), bvh_width=width)
    assert bufs.bvh_width == width
    m = 20000
    centre = verts.mean(axis=0)
    # Targets: points on random edges, pushed into one of the edge's two triangles by 1e-7 .. 1e-1 of the
    # distance to that triangle's centroid.
    owners = {}
    for f, tri in enumerate(tris):
        for i, j in ((0, 1), (1, 2), (2, 0)):
            owners.setdefault(tuple(sorted((tri[i], tri[j]))), []).append(f)
    all_edges = edges(tris)
    e = all_edges[rng.integers(0, len(all_edges), m)]
    k = np.array([owners[tuple(x)][side] for x, side in zip(e, rng.integers(0, 2, m))])
    a, b = verts[e[:, 0]], verts[e[:, 1]]
    on_edge = a + rng.uniform(0, 1, (m, 1)) * (b - a)
    tri_c = verts[tris].mean(axis=1)
    target = on_edge + (tri_c[k] - on_edge) * 10.0 ** rng.uniform(-7, -1, (m, 1))
    org = np.broadcast_to(centre, (m, 3))
    local = grazing_directions(rng, m)
    outward = rng.random(m) < 0.25
    local[outward, 2] *= -1
    p, h, d = run_rays(ctx, queue, kernel, bufs, org, target - centre, local)
    first, second = p[:, 3].view(np.uint32), h[:, 3].view(np.uint32)
    assert (first != 0xFFFFFFFF).all(), "a ray from inside a closed mesh found nothing"
    hit = second != 0xFFFFFFFF
    assert np.array_equal(hit, d[:, 3] > 0), "closest-hit and any-hit disagree"
    escaped_in = ~outward & ~hit
    assert not escaped_in.any(), f"{escaped_in.sum()} of {(~outward).sum()} inward rays left the closed mesh"
    reentered = outward & hit
    assert not reentered.any(), f"{reentered.sum()} of {outward.sum()} outward rays hit the mesh again"
    # The inward ray's hit is on another plane than the point it left (own triangle or a coplanar one).
    t = verts[tris]
    nrm = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    f, g = bufs.triangle_numbers(first[~outward]), bufs.triangle_numbers(second[~outward])
    size = np.ptp(verts, axis=0).max()
    same = (np.abs(np.sum(nrm[f] * nrm[g], 1)) > 1 - 1e-9) & \
        (np.abs(np.sum((t[g, 0] - t[f, 0]) * nrm[f], 1)) < 1e-6 * size)
    assert not same.any(), f"{same.sum()} spawned rays re-hit their own plane"


# -------------------------------------------------------------------------------------------- furnace
def inward(verts, tris):
    """The triangles of a convex mesh wound so their normals point inside (an area light emits that way)."""
    t = verts[tris]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    out = np.sum(n * (t.mean(axis=1) - verts.mean(axis=0)), 1) > 0
    return np.where(out[:, None], tris[:, ::-1], tris)


FURNACE_MESHES = {
    "cube": lambda: (None, None),      # analytic_scenes.furnace_scene: the 2 x 2 x 2 box, two triangles a face
    "uvsphere": MESHES["uvsphere"],
}


@pytest.mark.parametrize("width", [2, 4])
@pytest.mark.parametrize("mesh", sorted(FURNACE_MESHES))
def test_furnace_direct_mats_a_million_samples(tmp_path, mesh, width):
    """Inside a closed box (or UV sphere), every wall diffuse rho = 0.8 and emitting 1: direct_mats sees
    1 + 0.8 exactly in every sample unless a BSDF-sampled ray leaves the mesh or re-hits its own wall from
    behind. 250 x 250 pixels x 16 spp = 10^6 samples. Before the normal offsets the cube gave 1.799976
    (z = -5.5: 30 pixels lost a sample, all along the box's edges, where tmin skipped the next wall)."""
    rho = 0.8
    if mesh == "cube":
        xml = A.furnace_scene(tmp_path, "direct_mats", rho=rho)
    else:
        verts, tris = FURNACE_MESHES[mesh]()
        c = verts.mean(axis=0)
        body = (f'<bsdf type="diffuse"><color name="albedo" value="{rho}"/></bsdf>'
                f'<emitter type="area"><color name="radiance" value="1"/></emitter>')
        xml = mesh_scene(tmp_path, verts, inward(verts, tris), body=body).read_text()
        xml = xml.replace('<integrator type="normals"/>', '<integrator type="direct_mats"/>')
        xml = xml.replace(A.camera(), A.camera(width=4, height=4, fov=100, target=(0.3, 0.2, -1), origin=c))
    xml = xml.replace('<integer name="width" value="4"/>', '<integer name="width" value="250"/>')
    xml = xml.replace('<integer name="height" value="4"/>', '<integer name="height" value="250"/>')
    path = tmp_path / "furnace.xml"
    path.write_text(xml)
    scene = load_scene(path)
    film = Renderer(scene, buffers=pack_scene(scene, bvh_width=width)).render(spp=16, seed=7)
    assert film.image.shape[:2] == (250, 250)
    res = compare_mean_to_value(film, 1 + rho, 0.01)
    lost = int((film.image[..., 0] < 1.8 - 1e-4).sum())
    assert res.passed, (res.message, film.image.mean(), f"{lost} pixels lost a sample")
