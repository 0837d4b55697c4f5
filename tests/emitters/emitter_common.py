"""What the emitters' test files share (tests/emitters/test_<name>.py, tests/test_emitters.py,
tests/test_mitsuba_emitters.py): emitters on the device through one test program (its kernels sample an emitter or
the scene's selection, trace the pdf of directions, evaluate the environment and the radiance seen by a ray), the
scenes the Nori emitters are tested in, and the chi-square and per-sample checks:

* chi-square: directions drawn by each emitter's sample() against its own pdf(). The expected density of a
  direction is found by tracing it: for meshes, the sum of pdf() over every point where the ray meets the
  emitter (a mesh seen from outside is met twice, and the sampler picks points on both sides); for analytic
  spheres and infinite lights, pdf() of the direction. Šidák-corrected over all cases (CHI2_CASES).
* per sample: weight == eval / pdf, pdf() agrees with sample()'s pdf, a ray traced along the sample sees the
  same pdf.
"""
import numpy as np
import pyopencl as cl
import pytest

from clrender.device.dispatch import flag_defines as layout_flags
from clrender.device.program import build_program
from clrender.loader import load_scene
from clrender.pack import pack_scene
from clrender.scene import registry
from clrender.scene.transform import Transform
from clrender.testing.chi2 import bin_directions, chi2_test, expected_from_pdf, integration_directions
from icosphere import icosphere

LOCAL = 64

SRC = r"""
#include "emitter.h"

/* One emitter sample per work-item. e == NONE: scene-level selection (vxyz(u)), else emitter e (u.xy).
   wi_pdf = (wi, q.pdf); w_dist = (weight, q.dist); p_delta = (p, delta); n_em = (n, emitter);
   chk = (emitter_pdf(q) [scene-level: scene_emitter_pdf], emitter_pdf(q) of the chosen one, occluded,
          pdf through a traced ray, or -1 when the ray sees another point); ev = (emitter_eval(q), hit t). */
__kernel void sample_em(SCENE_ARGS, uint e, uint n, __global const float4* refs, __global const float4* us,
                        __global float4* wi_pdf, __global float4* w_dist, __global float4* p_delta,
                        __global float4* n_em, __global float4* chk, __global float4* ev) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    EmitterQuery q;
    q.ref = vxyz(refs[i]);
    float4 u = us[i];
    vec3 w;
    uint chosen = e;
    if (e == NONE) {
        w = scene_sample_emitter(&sd, &q, vxyz(u));
        chosen = q.emitter;
    } else {
        w = emitter_sample(&sd, e, &q, u.xy);
    }
    float pdf_again = (e == NONE) ? scene_emitter_pdf(&sd, chosen, &q) : emitter_pdf(&sd, e, &q);
    float pdf_one = chosen != NONE ? emitter_pdf(&sd, chosen, &q) : 0.0f;
    vec3 L = chosen != NONE ? emitter_eval(&sd, chosen, &q) : v3s(0.0f);
    float occl = (q.pdf > 0.0f && scene_occluded(&sd, q.ref, q.wi, ray_eps(q.ref), q.dist * (1.0f - 1e-4f)))
               ? 1.0f : 0.0f;
    float pdf_hit = -1.0f, t_hit = -1.0f;
    if (q.pdf > 0.0f && !q.delta && isfinite(q.dist)) {
        Ray r = spawn_ray(q.ref, q.wi);
        Intersection its;
        if (scene_intersect(&sd, &r, &its)) {
            t_hit = its.t;
            if (fabs(its.t - q.dist) <= 1e-3f * q.dist && sd.shapes[its.shape].emitter == chosen) {
                EmitterQuery h;
                emitter_query_from_hit(&h, q.ref, &its);
                pdf_hit = emitter_pdf(&sd, chosen, &h);
            }
        }
    }
    wi_pdf[i] = vf4(q.wi, q.pdf);
    w_dist[i] = vf4(w, q.dist);
    p_delta[i] = vf4(q.p, (float)q.delta);
    n_em[i] = vf4(q.n, chosen == NONE ? -1.0f : (float)chosen);
    chk[i] = (float4)(pdf_again, pdf_one, occl, pdf_hit);
    ev[i] = vf4(L, t_hit);
}

/* Density of directions of emitter e at ref, for each direction. mode 0: every point the ray meets on the
   emitter contributes pdf() (meshes); 1: the first hit only (analytic spheres: a density per direction);
   2: like 0, but with the WRONG per-point pdf dist^2 / A (no cosine at the light). Infinite lights: pdf()
   of the direction. */
__kernel void pdf_dirs(SCENE_ARGS, uint e, uint mode, uint n, __global const float4* ref4,
                       __global const float4* dirs, __global float* out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    vec3 ref = vxyz(ref4[0]), d = vxyz(dirs[i]);
    if (sd.emitters[e].flags & EMITTER_INFINITE) {
        EmitterQuery q;
        emitter_query_from_direction(&sd, &q, ref, d);
        out[i] = emitter_pdf(&sd, e, &q);
        return;
    }
    float sum = 0.0f, tmin = 0.0f;
    for (int k = 0; k < 64; ++k) {
        Ray r = spawn_ray(ref, d);
        r.tmin = tmin;
        Intersection its;
        if (!scene_intersect(&sd, &r, &its)) break;
        tmin = its.t * (1.0f + 1e-5f) + 1e-6f;
        if (sd.shapes[its.shape].emitter != e) continue;
        EmitterQuery q;
        emitter_query_from_hit(&q, ref, &its);
        float pdf = emitter_pdf(&sd, e, &q);
        if (mode == 2u) pdf *= fabs(dot3(q.ng, q.wi));
        sum += pdf;
        if (mode == 1u) break;
    }
    out[i] = sum;
}

/* Escaping directions: (scene_eval_environment, scene_environment_pdf). */
__kernel void environment(SCENE_ARGS, uint n, __global const float4* dirs, __global float4* out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    vec3 d = vxyz(dirs[i]);
    out[i] = vf4(scene_eval_environment(&sd, d), scene_environment_pdf(&sd, d));
}

/* Camera-style rays: (area_emitter_Le toward the ray origin, 1 if hit). */
__kernel void hit_le(SCENE_ARGS, uint n, __global const float4* org, __global const float4* dirs,
                     __global float4* out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    Ray r = spawn_ray(vxyz(org[i]), vxyz(dirs[i]));
    Intersection its;
    if (scene_intersect(&sd, &r, &its)) out[i] = vf4(area_emitter_Le(&sd, &its, vneg(vxyz(dirs[i]))), 1.0f);
    else out[i] = (float4)(0.0f);
}
"""


# ------------------------------------------------------------------------------------------------ device
@pytest.fixture(scope="session")
def kernels(ctx):
    prg = build_program(ctx, SRC)
    return {name: cl.Kernel(prg, name) for name in ("sample_em", "pdf_dirs", "environment", "hit_le")}


class Dev:
    """A packed scene on the device plus the launch helpers the tests need."""

    def __init__(self, ctx, queue, kernels, buffers):
        self.ctx, self.queue, self.k, self.b = ctx, queue, kernels, buffers
        ro = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
        self.scene = [cl.Buffer(ctx, ro, hostbuf=np.ascontiguousarray(a)) for a in buffers.scene_arrays()]

    def _in(self, a):
        a = np.ascontiguousarray(a, np.float32)
        if a.ndim == 2 and a.shape[1] == 3:
            a = np.concatenate([a, np.zeros((len(a), 1), np.float32)], axis=1)
        return cl.Buffer(self.ctx, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR, hostbuf=a)

    def _out(self, n, width=4):
        return cl.Buffer(self.ctx, cl.mem_flags.WRITE_ONLY, size=max(n, 1) * width * 4)

    def _run(self, name, n, args, outs, widths):
        k = self.k[name]
        k.set_args(*self.scene, *args)
        gsize = (n + LOCAL - 1) // LOCAL * LOCAL
        cl.enqueue_nd_range_kernel(self.queue, k, (gsize,), (LOCAL,))
        res = []
        for buf, w in zip(outs, widths):
            a = np.empty((n, w) if w > 1 else n, np.float32)
            cl.enqueue_copy(self.queue, a, buf)
            res.append(a)
        return res

    def sample(self, e, refs, u):
        """Emitter e (or NONE: scene-level) sampled at refs (N,3) with uniforms u (N,3)."""
        n = len(u)
        refs = np.broadcast_to(np.asarray(refs, np.float32), (n, 3))
        u4 = np.zeros((n, 4), np.float32)
        u4[:, :u.shape[1]] = u
        outs = [self._out(n) for _ in range(6)]
        r = self._run("sample_em", n, [np.uint32(e), np.uint32(n), self._in(refs), self._in(u4), *outs],
                      outs, [4] * 6)
        wi_pdf, w_dist, p_delta, n_em, chk, ev = r
        return dict(wi=wi_pdf[:, :3], pdf=wi_pdf[:, 3], w=w_dist[:, :3], dist=w_dist[:, 3], p=p_delta[:, :3],
                    delta=p_delta[:, 3], n=n_em[:, :3], emitter=n_em[:, 3].astype(np.int64), pdf_again=chk[:, 0],
                    pdf_one=chk[:, 1], occluded=chk[:, 2], pdf_hit=chk[:, 3], eval=ev[:, :3], t_hit=ev[:, 3])

    def pdf_dirs(self, e, ref, dirs, mode=0):
        n = len(dirs)
        out = self._out(n, 1)
        ref4 = np.zeros((1, 4), np.float32)
        ref4[0, :3] = ref
        return self._run("pdf_dirs", n, [np.uint32(e), np.uint32(mode), np.uint32(n), self._in(ref4),
                                         self._in(dirs), out], [out], [1])[0]

    def environment(self, dirs):
        n = len(dirs)
        out = self._out(n)
        return self._run("environment", n, [np.uint32(n), self._in(dirs), out], [out], [4])[0]

    def hit_le(self, org, dirs):
        n = len(dirs)
        out = self._out(n)
        org = np.broadcast_to(np.asarray(org, np.float32), (n, 3))
        return self._run("hit_le", n, [np.uint32(n), self._in(org), self._in(dirs), out], [out], [4])[0]


# ------------------------------------------------------------------------------------------------ scenes
HEADER = """<scene>
    <integrator type="normals"/>
    <camera type="perspective"><integer name="width" value="4"/><integer name="height" value="4"/></camera>
"""


def obj_text(verts, faces, normals=None):
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in verts]
    if normals is not None:
        lines += [f"vn {x:.9g} {y:.9g} {z:.9g}" for x, y, z in normals]
        lines += [f"f {a + 1}//{a + 1} {b + 1}//{b + 1} {c + 1}//{c + 1}" for a, b, c in faces]
    else:
        lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    return "\n".join(lines) + "\n"


def tris_obj(tris):
    """Separate triangles (T,3,3) as an OBJ without normals (shading normal = winding normal)."""
    tris = np.asarray(tris, float)
    return obj_text(tris.reshape(-1, 3), np.arange(3 * len(tris)).reshape(-1, 3))


def area_mesh_xml(name, radiance=(1, 1, 1)):
    r = ", ".join(str(x) for x in radiance)
    return (f'<mesh type="obj"><string name="filename" value="{name}"/>'
            f'<emitter type="area"><color name="radiance" value="{r}"/></emitter></mesh>\n')


def write_scene(tmp, stem, body, objs=None):
    for fname, text in (objs or {}).items():
        (tmp / fname).write_text(text)
    path = tmp / f"{stem}.xml"
    path.write_text(HEADER + body + "</scene>\n")
    return pack_scene(load_scene(path))


def unequal_triangles():
    """One big triangle below the reference point (the origin) and tiny ones at random distances and
    orientations: areas differ by up to four orders of magnitude."""
    rng = np.random.default_rng(7)
    tris = [np.array([[-1.5, -0.5, -1.0], [1.5, -0.6, -1.0], [0.0, -0.4, 1.5]])]
    for k in range(7):
        c = rng.normal(size=3)
        c = c / np.linalg.norm(c) * rng.uniform(0.4, 2.5)
        size = np.linalg.norm(c) * rng.uniform(0.15, 0.5)   # tiny in area, not in solid angle
        frame = np.linalg.qr(rng.normal(size=(3, 3)))[0]
        local = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.3, 0.9, 0.0]]) - [0.43, 0.3, 0.0]
        tris.append(c + size * local @ frame.T)
    return np.array(tris)


def quad(c, u, v):
    """Two triangles c ± u ± v, wound so the normal is u x v."""
    c, u, v = map(np.asarray, (c, u, v))
    a, b, cc, d = c - u - v, c + u - v, c + u + v, c - u + v
    return [[a, b, cc], [a, cc, d]]


# Reference points for the chi-square cases.
ORIGIN = np.zeros(3)
SUN_ROTATE = '<transform name="toWorld"><rotate axis="-0.8575, -0.5145, 0" angle="60.245"/></transform>'


@pytest.fixture(scope="module")
def scenes(tmp_path_factory, ctx, queue, kernels):
    tmp = tmp_path_factory.mktemp("emitters")
    out = {}

    def dev(stem, body, objs=None):
        out[stem] = Dev(ctx, queue, kernels, write_scene(tmp, stem, body, objs))

    dev("unequal", area_mesh_xml("unequal.obj"), {"unequal.obj": tris_obj(unequal_triangles())})
    # A closed smooth-shaded mesh seen from outside: every direction meets it twice, and the shading normals
    # (the sphere's) differ from the facets' (the Jacobian must use the facets').
    v, f = icosphere(1)
    c = np.array([0.9, 0.3, -0.2])
    (tmp / "ico.obj").write_text(obj_text(v * 0.8 + c, f, v))
    dev("closed", area_mesh_xml("ico.obj"))
    # Overlapping sheets: in front of the reference, behind it, one seen from its back, one hidden in part.
    sheets = (quad([0, 0, 1.0], [1, 0, 0], [0, 0.8, 0]) + quad([0.3, 0.2, 2.0], [0, 1.6, 0], [1.5, 0, 0])
              + quad([0.2, -0.3, -0.7], [0.4, 0, 0], [0, 0.5, 0.1]) + quad([-0.9, 0.5, 0.2], [0, 0.3, 0.3], [0, 0.3, -0.3]))
    dev("sheets", area_mesh_xml("sheets.obj"), {"sheets.obj": tris_obj(sheets)})
    dev("sphere", '<mesh type="sphere"><point name="center" value="0.5, 1.2, -0.3"/><float name="radius" value="0.7"/>'
                  '<emitter type="area"><color name="radiance" value="3, 2, 1"/></emitter></mesh>\n')
    for deg in (10, 60, 180):
        dev(f"disk{deg}", f'<emitter type="distantdisk"><color name="radiance" value="2, 3, 4"/>'
                          f'<float name="thetaA" value="{deg}"/>{SUN_ROTATE}</emitter>\n')
    dev("constant", '<emitter type="constant"><color name="radiance" value="0.5, 1, 2"/></emitter>\n')
    # Unoccluded lights for the per-sample checks: a planar quad light above a ground plane, a small far sphere.
    ground = quad([0, 0, 0], [0, 0, 5], [5, 0, 0])
    (tmp / "ground.obj").write_text(tris_obj(ground))
    (tmp / "ceiling.obj").write_text(tris_obj(quad([0.3, 2.0, 0.1], [0.5, 0, 0], [0, 0, 0.4])))
    (tmp / "ceiling_n.obj").write_text(obj_text(np.array(quad([0.3, 2.0, 0.1], [0.5, 0, 0], [0, 0, 0.4])).reshape(-1, 3),
                                                np.arange(6).reshape(2, 3), np.tile([[0.0, -1.0, 0.0]], (6, 1))))
    ground_xml = '<mesh type="obj"><string name="filename" value="ground.obj"/></mesh>\n'
    dev("ceiling", ground_xml + area_mesh_xml("ceiling_n.obj", (4, 5, 6)))
    dev("far_sphere", ground_xml + '<mesh type="sphere"><point name="center" value="3, 9, -4"/><float name="radius" '
                      'value="0.05"/><emitter type="area"><color name="radiance" value="7, 7, 7"/></emitter></mesh>\n')
    dev("sun", ground_xml + f'<emitter type="distantdisk"><color name="radiance" value="50, 50, 50"/>'
                            f'<float name="thetaA" value="6"/>{SUN_ROTATE}</emitter>\n'
                            '<emitter type="constant"><color name="radiance" value="0.12, 0.15, 0.2"/></emitter>\n')
    dev("delta", ground_xml + '<emitter type="point"><point name="position" value="-1, 3, 2"/>'
                              '<color name="power" value="120, 100, 80"/></emitter>\n'
                              '<emitter type="distant"><vector name="direction" value="0.4, -1, -0.5"/>'
                              '<color name="irradiance" value="1, 0.95, 0.85"/></emitter>\n')
    dev("three", area_mesh_xml("ceiling.obj", (4, 5, 6)) +
        '<emitter type="point"><point name="position" value="-1, 3, 2"/><color name="power" value="10"/></emitter>\n'
        '<emitter type="distantdisk"><color name="radiance" value="1"/><float name="thetaA" value="30"/></emitter>\n')
    return out


# ----------------------------------------------------------------------------------------------- chi-square
# (scene, emitter index, reference point, pdf mode, samples, integration sub-grid)
CHI2_CASES = {
    "area-unequal-triangles": ("unequal", 0, ORIGIN, 0, 200_000, 16),
    "area-closed-smooth-mesh": ("closed", 0, ORIGIN, 0, 200_000, 16),
    "area-overlapping-sheets": ("sheets", 0, np.array([0.1, 0.05, 0.3]), 0, 200_000, 16),
    "sphere-outside": ("sphere", 0, ORIGIN, 1, 200_000, 16),
    "sphere-inside": ("sphere", 0, np.array([0.7, 1.0, -0.1]), 1, 200_000, 16),
    "distantdisk-10": ("disk10", 0, ORIGIN, 0, 100_000, 16),
    "distantdisk-60": ("disk60", 0, ORIGIN, 0, 200_000, 16),
    "distantdisk-180": ("disk180", 0, ORIGIN, 0, 200_000, 16),
    "constant": ("constant", 0, ORIGIN, 0, 200_000, 16),
}
RES = 10


def cell_directions(cells, res, fine):
    """A fine x fine midpoint grid in (theta, phi) inside each of the given (i, j) cells, and the solid angle
    of each point (sin theta dtheta dphi). Uniform in theta rather than cos theta, so that slivers near the
    poles are resolved too."""
    k = (np.arange(fine) + 0.5) / fine
    i, j = np.asarray(cells).T
    t0 = np.arccos(np.clip(-1.0 + i * (2.0 / res), -1, 1))               # z = -1 + i 2/res: theta decreases
    t1 = np.arccos(np.clip(-1.0 + (i + 1) * (2.0 / res), -1, 1))
    theta = t0[:, None] + (t1 - t0)[:, None] * k[None]                    # (C, fine)
    phi = (j[:, None] + k[None]) * (np.pi / res)
    T_ = np.repeat(theta[:, :, None], fine, axis=2)
    P = np.repeat(phi[:, None, :], fine, axis=1)
    dirs = np.stack([np.sin(T_) * np.cos(P), np.sin(T_) * np.sin(P), np.cos(T_)], axis=-1).reshape(-1, 3)
    dw = (np.sin(T_) * np.abs(t1 - t0)[:, None, None] / fine * (np.pi / res) / fine).reshape(len(cells), -1)
    return dirs, dw


def expected_counts(dev, e, ref, mode, n, sub, observed, fine=128):
    """Expected counts: the midpoint rule of clrender.testing.chi2 on a (res sub)^2 grid, then every cell in
    which the pdf jumps (an edge of the emitter or of one of its triangles crosses it), or which is empty on
    the coarse grid but next to a non-empty cell or holding samples, integrated again on a fine x fine grid,
    so that thin slivers of an emitter in a cell's corner are not lost. (Choosing where to integrate more
    finely by looking at the samples changes only the accuracy of the integral, never its value.)"""
    dirs, _ = integration_directions(RES, sub)
    pdf = dev.pdf_dirs(e, ref, dirs.astype(np.float32), mode).astype(np.float64)
    exp = expected_from_pdf(pdf, RES, sub, n)
    v = pdf.reshape(RES, sub, 2 * RES, sub).transpose(0, 2, 1, 3)       # (i, j, sub, sub)
    lo = np.minimum(v[..., 1:, :], v[..., :-1, :]).min(axis=(2, 3))
    hi = np.maximum(v[..., 1:, :], v[..., :-1, :]).max(axis=(2, 3))
    a, b = v[..., 1:, :], v[..., :-1, :]
    jump_z = (np.abs(a - b) > 0.2 * np.maximum(a, b)).any(axis=(2, 3))
    a, b = v[..., :, 1:], v[..., :, :-1]
    jump_p = (np.abs(a - b) > 0.2 * np.maximum(a, b)).any(axis=(2, 3))
    # cells next to a non-empty one may hold a sliver the coarse grid missed
    nonzero = hi > 0
    near = nonzero.copy()
    near[1:] |= nonzero[:-1]
    near[:-1] |= nonzero[1:]
    near |= np.roll(nonzero, 1, axis=1) | np.roll(nonzero, -1, axis=1)
    refine = jump_z | jump_p | ((near | (observed > 0)) & (lo == 0))
    cells = np.argwhere(refine)
    if len(cells):
        fdirs, dw = cell_directions(cells, RES, fine)
        fpdf = dev.pdf_dirs(e, ref, fdirs.astype(np.float32), mode).astype(np.float64).reshape(len(cells), -1)
        exp[cells[:, 0], cells[:, 1]] = (fpdf * dw).sum(axis=1) * n
    return exp


def run_chi2(dev, e, ref, mode, n, sub, seed, n_tests=len(CHI2_CASES)):
    u = np.random.default_rng(seed).random((n, 2), dtype=np.float32)
    s = dev.sample(e, ref, u)
    obs = bin_directions(s["wi"], RES)
    exp = expected_counts(dev, e, ref, mode, n, sub, obs)
    return chi2_test(obs, exp, alpha=0.01, n_tests=n_tests)


# ------------------------------------------------------------------------------------------ per-sample checks
def _refs(rng, n, lo, hi):
    return rng.uniform(lo, hi, (n, 3)).astype(np.float32)


WEIGHT_CASES = {
    # scene, emitter, reference points (low corner, high corner)
    "unequal": ("unequal", 0, ([-0.2] * 3, [0.2] * 3)),
    "closed": ("closed", 0, ([-0.5] * 3, [0.0] * 3)),
    "ceiling": ("ceiling", 0, ([-1.0, 0.1, -1.0], [1.0, 1.5, 1.0])),
    "sphere": ("sphere", 0, ([-0.5, -0.5, -0.5], [0.0, 0.2, 0.0])),
    "far_sphere": ("far_sphere", 0, ([-1.0, 0.1, -1.0], [1.0, 1.5, 1.0])),
    "disk10": ("disk10", 0, ([-1.0] * 3, [1.0] * 3)),
    "disk180": ("disk180", 0, ([-1.0] * 3, [1.0] * 3)),
    "constant": ("constant", 0, ([-1.0] * 3, [1.0] * 3)),
}



def check_chi2_case(scenes, case):
    """Chi-square of CHI2_CASES[case]: the emitter's sampled directions against its own pdf, traced (seeded and
    Šidák-corrected over every case of CHI2_CASES, as when they were one module)."""
    stem, e, ref, mode, n, sub = CHI2_CASES[case]
    r = run_chi2(scenes[stem], e, ref, mode, n, sub, seed=1000 + list(CHI2_CASES).index(case))
    assert r.passed, f"{case}: {r.message}"
    assert r.dof >= 3, f"{case}: too few cells for a meaningful test ({r.dof})"


def check_weight_case(scenes, case):
    """WEIGHT_CASES[case]: per sample, weight == eval / pdf, pdf() agrees with sample()'s, and for a surface light
    the sampled point lies at ref + dist wi and a ray traced along wi reports the same pdf."""
    stem, e, (lo, hi) = WEIGHT_CASES[case]
    rng = np.random.default_rng(5)
    n = 20_000
    refs = _refs(rng, n, lo, hi)
    s = scenes[stem].sample(e, refs, rng.random((n, 2), dtype=np.float32))
    assert np.all(s["pdf"] > 0) and np.all(np.isfinite(s["w"])) and np.all(s["delta"] == 0)
    np.testing.assert_allclose(np.linalg.norm(s["wi"], axis=1), 1, atol=1e-5)
    np.testing.assert_allclose(s["pdf_again"], s["pdf"], rtol=2e-4)
    expect = s["eval"] / s["pdf_again"][:, None]
    np.testing.assert_allclose(s["w"], expect, rtol=2e-4, atol=1e-6)
    assert np.any(s["w"] > 0)
    row = scenes[stem].b.emitters[e]
    if row["flags"] & layout_flags()["EMITTER_SURFACE"]:
        # the sampled point lies at p = ref + dist * wi, and a ray traced along wi reports the same pdf
        np.testing.assert_allclose(s["dist"], np.linalg.norm(s["p"] - refs, axis=1), rtol=1e-4)
        seen = s["pdf_hit"] >= 0
        assert seen.mean() > 0.1
        # (a ray landing on the neighbour of the sampled triangle, at their shared edge, sees its facet normal)
        same = np.isclose(s["pdf_hit"][seen], s["pdf"][seen], rtol=2e-3)
        assert same.mean() > 0.995, f"{(~same).sum()} of {same.size} traced pdfs differ"
    else:
        assert np.all(np.isinf(s["dist"]))


def check_noiseless_render(tmp_path, scene_of, value):
    """Render `scene_of(folder, "path_mis")` (a scene of tests/analytic_scenes.py lit by a delta light, so without
    noise) at 16 spp: every pixel equals `value` to float precision."""
    import clrender

    p = tmp_path / "scene.xml"
    p.write_text(scene_of(tmp_path, "path_mis"))
    film = clrender.render(clrender.load_scene(p), spp=16, seed=1)
    np.testing.assert_allclose(film.image, np.broadcast_to(value, film.image.shape), rtol=2e-4)


# ------------------------------------------------------------------------------------- Mitsuba's emitters
def mitsuba(type_name, **props):
    """A Mitsuba-format emitter made from code: props name=(tag, value)."""
    return registry.instantiate("emitter", type_name, props, fmt="mitsuba")


def device(tmp, ctx, queue, kernels, emitters, stem="s", selection="uniform"):
    """A ground quad (for the scene bounds) lit by the given emitter objects, packed and on the device."""
    (tmp / "ground.obj").write_text(tris_obj(quad([0, 0, 0], [0, 0, 5], [5, 0, 0])))
    path = tmp / f"{stem}.xml"
    path.write_text(HEADER + '<mesh type="obj"><string name="filename" value="ground.obj"/></mesh>\n</scene>\n')
    scene = load_scene(path)
    scene.emitters.extend(emitters)
    return Dev(ctx, queue, kernels, pack_scene(scene, emitter_selection=selection))


def unit(v):
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def sky_image(w=24, h=12):
    """A small lat-long test map: a dim gradient, a bright warm patch and a black band (generated here)."""
    y, x = np.mgrid[0:h, 0:w]
    img = np.stack([0.2 + 0.3 * x / w, 0.3 + 0.2 * y / h, 0.5 - 0.3 * y / h], axis=-1)
    img[2:4, 5:8] = [40.0, 30.0, 10.0]
    img[8, :] = 0.0
    return img.astype(np.float32)


def write_exr(path, img):
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, {"RGB": np.ascontiguousarray(img, np.float32)}).write(str(path))


@pytest.fixture(scope="module")
def envmaps(tmp_path_factory, ctx, queue, kernels):
    tmp = tmp_path_factory.mktemp("envmap")
    write_exr(tmp / "sky.exr", sky_image())
    rot = Transform.rotate([0.3, 1.0, -0.2], 70.0)
    em = mitsuba("envmap", filename=("string", str(tmp / "sky.exr")), scale=("float", 1.5),
                 to_world=("transform", rot))
    return em, device(tmp, ctx, queue, kernels, [em])
