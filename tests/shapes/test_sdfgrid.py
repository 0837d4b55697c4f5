"""Mitsuba 3's SDF grid (clrender/shapes/sdfgrid.py, kernels/shapes/sdfgrid.h, bvh_common.h bvh_isect_voxel): the
kernel's hits and geometric normals against a float64 reference that marches the trilinear field along each ray
(a grid of unequal resolutions, turned and scaled, alone and through an instance, in every BVH width), spawned rays
that neither re-hit the surface nor pass through it, a rendered furnace, and its errors. Whole renders against
Mitsuba's (smooth shading normals, instancing, a glossy and a diffuse grid) are the twins `sdfgrid` and
`sdfgrid_normals` (tests/test_mitsuba_twins.py). An SDF grid has no area and cannot emit (as in Mitsuba): nothing of
it is sampled, which the coverage test lists as its gap."""
import numpy as np
import pyopencl as cl
import pytest

from clrender.device.program import build_program
from clrender.errors import SceneError
from clrender.loader import load_scene
from clrender.pack import pack_scene
from clrender.volumes.gridvolume import write_vol

from .shape_common import check_shape_furnace_render

RES = (13, 9, 11)            # x, y, z: unequal on purpose (Mitsuba 3.9.1 misplaces the voxels of such grids)


def ball_and_bar(res=RES) -> np.ndarray:
    """Signed distances (z, y, x) at the grid points of a ball joined to a bar (a concave seam), scaled by 3."""
    x, y, z = (np.arange(n) / (n - 1) for n in res)
    zz, yy, xx = np.meshgrid(z, y, x, indexing="ij")
    ball = np.sqrt((xx - 0.4) ** 2 + (yy - 0.5) ** 2 + (zz - 0.45) ** 2) - 0.3
    q = np.abs(np.stack([xx - 0.7, yy - 0.55, zz - 0.5])) - np.array([0.25, 0.12, 0.1])[:, None, None, None]
    bar = np.linalg.norm(np.maximum(q, 0), axis=0) + np.minimum(q.max(axis=0), 0)
    return (3.0 * np.minimum(ball, bar)).astype(np.float32)


def trilinear(values, g):
    """The grid's interpolation at grid coordinates g (N, 3), indices clamped (float64)."""
    v = np.asarray(values, np.float64)
    n = np.array(v.shape[::-1])
    i0 = np.floor(g).astype(np.int64)
    f = g - i0
    out = np.zeros(len(g))
    for c in range(8):
        b = np.array([c & 1, (c >> 1) & 1, (c >> 2) & 1])
        idx = np.clip(i0 + b, 0, n - 1)
        w = np.prod(np.where(b, f, 1 - f), axis=1)
        out += w * v[idx[:, 2], idx[:, 1], idx[:, 0]]
    return out


def reference_hits(values, to_world, o, d, steps):
    """The first zero of the field along each ray (float64): the ray marched in `steps` through the grid's box,
    the first sign change refined by bisection. t = inf where there is none."""
    res = np.array(values.shape[::-1], np.float64)
    a = np.linalg.inv(to_world)[:3] * (res - 1)[:, None]
    og = o @ a[:, :3].T + a[:, 3]
    dg = d @ a[:, :3].T
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (0 - og) / dg
        t1 = (res - 1 - og) / dg
    tn = np.nanmax(np.minimum(t0, t1), axis=1).clip(0)
    tf = np.nanmin(np.maximum(t0, t1), axis=1)
    out = np.full(len(o), np.inf)
    k = np.nonzero(tn < tf)[0]
    ts = tn[k, None] + (tf - tn)[k, None] * np.linspace(0, 1, steps)[None]
    f = trilinear(values, (og[k, None] + ts[..., None] * dg[k, None]).reshape(-1, 3)).reshape(len(k), steps)
    change = f[:, :-1] * f[:, 1:] <= 0
    has = change.any(axis=1)
    k, ts, f, first = k[has], ts[has], f[has], np.argmax(change[has], axis=1)
    rows = np.arange(len(k))
    lo, hi, flo = ts[rows, first], ts[rows, first + 1], f[rows, first]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        fm = trilinear(values, og[k] + mid[:, None] * dg[k])
        same = (fm != 0) & ((fm < 0) == (flo < 0))
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    out[k] = 0.5 * (lo + hi)
    return out


def reference_normals(values, to_world, p):
    """The gradient of the trilinear interpolation of the voxel holding each point, as a world normal."""
    res = np.array(values.shape[::-1], np.float64)
    a = np.linalg.inv(to_world)[:3]
    g = (p @ a[:, :3].T + a[:, 3]) * (res - 1)
    v = np.clip(np.floor(g), 0, res - 2)
    grad = np.zeros_like(g)
    for k in range(3):
        hi, lo = g.copy(), g.copy()
        hi[:, k], lo[:, k] = v[:, k] + 1, v[:, k]
        grad[:, k] = (trilinear(values, hi) - trilinear(values, lo)) * (res[k] - 1)
    n = grad @ a[:, :3]                               # the normal's map: to_object's transpose
    return n / np.linalg.norm(n, axis=1, keepdims=True)


PROBE_SRC = r"""
#include "scene.h"
/* out0 = (t, ng), out1 = (shading normal, any-hit) of a ray, out2 = (where a ray spawned from the hit back toward
   the origin side lands: t of its hit or -1, any-hit), along -d reflected about ng (leaving on the ray's side). */
__kernel void probe(SCENE_ARGS, uint n, __global const float4* org, __global const float4* dir,
                    __global float4* out0, __global float4* out1, __global float4* out2) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    Ray r;
    r.o = vxyz(org[i]); r.d = vxyz(dir[i]); r.tmin = 0.0f; r.tmax = INFINITY;
    bool occ = scene_occluded(&sd, r.o, r.d, r.tmin, r.tmax);
    Intersection its;
    if (!scene_intersect(&sd, &r, &its)) {
        out0[i] = (float4)(0.0f, 0.0f, 0.0f, INFINITY);
        out1[i] = (float4)(0.0f, 0.0f, 0.0f, occ ? 1.0f : 0.0f);
        out2[i] = (float4)(-1.0f);
        return;
    }
    out0[i] = vf4(its.ng, its.t);
    out1[i] = vf4(its.sh.n, occ ? 1.0f : 0.0f);
    vec3 nf = dot3(its.ng, r.d) < 0.0f ? its.ng : vneg(its.ng);
    vec3 refl = vmad(nf, -2.0f * dot3(r.d, nf), r.d);
    Ray s = spawn_ray_from(&its, normalize3(refl));
    Intersection h;
    bool back = scene_intersect(&sd, &s, &h);
    out2[i] = (float4)(back ? h.t : -1.0f, scene_occluded(&sd, s.o, s.d, s.tmin, s.tmax) ? 1.0f : 0.0f, 0.0f, 0.0f);
}
"""


@pytest.fixture(scope="module", params=[2, 4, 8], ids=["bvh2", "bvh4", "bvh8"])
def probe(ctx, request):
    prg = build_program(ctx, PROBE_SRC, defines={"BVH_WIDTH": request.param})
    return cl.Kernel(prg, "probe"), request.param


def run_probe(ctx, queue, kernel, buffers, o, d):
    from test_watertight import run_rays

    return [a.astype(np.float64) for a in run_rays(ctx, queue, kernel, buffers, o, d)]


def aimed_rays(m, n, seed, length=3.0):
    """Rays from all around at n random points of the grid's inner box (taken to the world by m): origins, unit
    directions."""
    rng = np.random.default_rng(seed)
    target = (np.c_[rng.uniform(0.1, 0.95, n), rng.uniform(0.2, 0.8, n), rng.uniform(0.1, 0.9, n), np.ones(n)]
              @ m.T)[:, :3]
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return target - length * u, u


TO_WORLD = ('<scale x="1.6" y="0.9" z="1.2"/><translate x="-0.8" y="-0.45" z="-0.6"/>'
            '<rotate x="0.3" y="1" z="0.2" angle="40"/><translate x="0.2" y="0.1" z="-0.3"/>')


def grid_xml(tmp_path, instanced: bool, normals="smooth"):
    write_vol(tmp_path / "g.vol", ball_and_bar())
    shape = (f'<shape type="sdfgrid"><string name="filename" value="g.vol"/><string name="normals" value="{normals}"/>'
             '{tw}</shape>')
    if instanced:    # the same placement, split between the grid's own to_world and the instance's
        body = ('<shape type="shapegroup" id="g">' + shape.format(tw='<transform name="to_world"><scale x="1.6" '
                'y="0.9" z="1.2"/></transform>') + '</shape><shape type="instance"><ref id="g"/><transform '
                'name="to_world"><translate x="-0.8" y="-0.45" z="-0.6"/><rotate x="0.3" y="1" z="0.2" angle="40"/>'
                '<translate x="0.2" y="0.1" z="-0.3"/></transform></shape>')
    else:
        body = shape.format(tw=f'<transform name="to_world">{TO_WORLD}</transform>')
    (tmp_path / "s.xml").write_text('<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm">'
                                    '<integer name="width" value="4"/><integer name="height" value="4"/></film>'
                                    f'</sensor><emitter type="constant"/>{body}</scene>')
    return tmp_path / "s.xml"


def world_matrix():
    from clrender.scene.xmlparser import parse_string

    spec = parse_string(f'<scene version="3.0.0"><shape type="sdfgrid"><transform name="to_world">{TO_WORLD}'
                        '</transform></shape></scene>')
    return np.asarray(spec.children[0].props.get_transform("to_world").matrix, np.float64)


@pytest.mark.parametrize("instanced", [False, True], ids=["to_world", "instance"])
def test_hits_and_normals_match_a_marched_reference(tmp_path, ctx, queue, probe, instanced):
    """Rays from all around at points near the surface (many grazing it, some through the concave seam): the
    kernel's first hit (closest and any-hit alike) and geometric normal against the field marched in float64. A
    ray whose reference is ambiguous (two marches of different step disagree: a sliver thinner than a step) is
    left out; there must be few."""
    kernel, width = probe
    m = world_matrix()
    bufs = pack_scene(load_scene(grid_xml(tmp_path, instanced)), bvh_width=width)
    assert bufs.bvh_width == width
    o, u = aimed_rays(m, 1500, 3)
    d = u * np.random.default_rng(4).uniform(0.5, 2.0, (len(u), 1))   # unnormalised: t is in their units
    out0, out1, out2 = run_probe(ctx, queue, kernel, bufs, o, d)
    values = ball_and_bar()
    ref = reference_hits(values, m, o, d, 600)
    ref2 = reference_hits(values, m, o, d, 2400)
    with np.errstate(invalid="ignore"):
        clear = (np.isinf(ref) & np.isinf(ref2)) | (np.abs(ref - ref2) < 1e-9)
    assert clear.mean() > 0.98
    t = out0[:, 3]
    hit_ref = np.isfinite(ref)
    assert 0.3 < hit_ref[clear].mean() < 0.95           # the rays test both hits and misses
    assert np.array_equal(np.isfinite(t)[clear], hit_ref[clear])
    assert np.array_equal(out1[clear, 3] == 1, hit_ref[clear])     # any-hit agrees with closest hit
    both = clear & hit_ref
    scale = np.linalg.norm(d[both], axis=1)
    np.testing.assert_array_less(np.abs(t[both] - ref[both]) * scale, 2e-5)
    p = o[both] + ref[both, None] * d[both]
    ng = reference_normals(values, m, p)
    cos = np.abs(np.sum(out0[both, :3] * ng, axis=1))
    assert cos.min() > 1 - 1e-4, f"geometric normals off by up to {np.degrees(np.arccos(cos.min())):.3f} deg"
    assert np.all(np.sum(out0[both, :3] * ng, axis=1) > 0)          # outward: toward positive values
    sh = out1[both, :3]
    np.testing.assert_allclose(np.linalg.norm(sh, axis=1), 1, atol=1e-5)
    assert np.all(np.sum(sh * ng, axis=1) > 0.5)                    # smooth normals stay near the true ones


def test_spawned_rays_do_not_rehit_their_point(tmp_path, ctx, queue, probe):
    """Rays reflected off the surface leave it: the reflected ray's hit, if any, is not the point it left (t far
    above the offset's scale), and any-hit agrees with it."""
    kernel, width = probe
    bufs = pack_scene(load_scene(grid_xml(tmp_path, False)), bvh_width=width)
    m = world_matrix()
    out0, _, out2 = run_probe(ctx, queue, kernel, bufs, *aimed_rays(m, 3000, 5))
    hit = np.isfinite(out0[:, 3])
    assert hit.sum() > 1000
    again = out2[hit, 0]
    assert np.all((again < 0) | (again > 1e-3)), np.sort(again[again >= 0])[:5]
    assert np.array_equal(again >= 0, out2[hit, 1] == 1)


@pytest.mark.plugin("sdfgrid", "render")
def test_furnace_render(tmp_path):
    """The ball's top, turned and scaled by to_world, diffuse in a constant environment, shows its albedo: no ray
    leaving it comes back to the surface (with the analytic normal, the surface's own; smooth shading normals
    send some rays into it, as in Mitsuba). Mitsuba 3.9.1 renders this half black: it boxes the voxels of a
    rotated grid wrongly."""
    write_vol(tmp_path / "g.vol", ball_and_bar())
    shape = ('<shape type="sdfgrid"><string name="filename" value="g.vol"/><string name="normals" value="analytic"/>'
             '<transform name="to_world"><scale value="2"/><rotate z="1" angle="30"/></transform>{emitter}</shape>')
    c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
    m = np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) @ np.diag([2.0, 2.0, 2.0, 1.0])
    top = (m @ [0.4, 0.5, 0.77, 1])[:3]
    check_shape_furnace_render(tmp_path, shape, top + [0, 0, 3], top)


def test_errors(tmp_path):
    def load(shape, name="e.xml"):
        (tmp_path / name).write_text(f'<scene version="3.0.0">{shape}</scene>')
        return load_scene(tmp_path / name)

    write_vol(tmp_path / "g.vol", ball_and_bar())
    write_vol(tmp_path / "rgb.vol", np.zeros((3, 3, 3, 3)))
    write_vol(tmp_path / "flat.vol", np.ones((1, 4, 4)))
    write_vol(tmp_path / "empty.vol", np.ones((4, 4, 4)))
    with pytest.raises(SceneError, match="needs a <string name=\"filename\">") as e:
        load('<shape type="sdfgrid"/>')
    assert e.value.location is not None
    with pytest.raises(SceneError, match="3 channels; expected 1"):
        load('<shape type="sdfgrid"><string name="filename" value="rgb.vol"/></shape>')
    with pytest.raises(SceneError, match="at least 2 values along each axis"):
        load('<shape type="sdfgrid"><string name="filename" value="flat.vol"/></shape>')
    with pytest.raises(SceneError, match="no surface"):
        load('<shape type="sdfgrid"><string name="filename" value="empty.vol"/></shape>')
    with pytest.raises(SceneError, match="normals must be one of analytic, smooth"):
        load('<shape type="sdfgrid"><string name="filename" value="g.vol"/><string name="normals" value="flat"/>'
             '</shape>')
    with pytest.raises(SceneError, match="cannot carry an area emitter"):
        load('<shape type="sdfgrid"><string name="filename" value="g.vol"/><emitter type="area"/></shape>')
    with pytest.raises(SceneError, match="singular|invertible"):
        load('<shape type="sdfgrid"><string name="filename" value="g.vol"/><transform name="to_world">'
             '<scale x="0"/></transform></shape>')
    with pytest.raises(SceneError, match="not found"):
        load('<shape type="sdfgrid"><string name="filename" value="missing.vol"/></shape>')
