#!/usr/bin/env python
"""Regenerate every clrender scene (XML) and mesh under scenes/, deterministically.

    python scenes/build.py [--out DIR] [--check]
    python scenes/build.py --large-meshes     # only the large PLY meshes, if missing (they are not in git)

Default output folder: the folder of this script (scenes/).  Everything is generated here from
code (no third-party scene or mesh data): fixed float formatting, a fixed RNG seed, no timestamps,
so the XML and OBJ output is byte-for-byte reproducible; the large PLY meshes agree across CPUs to
float rounding (numpy's vectorised sin may differ in a last bit), so they are generated on demand and
compared by tolerance (see scenes/README.md).

Conventions used by all scenes
------------------------------
* World space is right-handed, +y is up.  Scenes are written in the *upstream* Nori dialect (wjakob/nori,
  clrender's default), whose camera shows camera +x on the image's left: a plain ``<lookat>`` (whose x
  axis is the viewer's left, cross(up, dir)) gives the unmirrored image.  E.g. the Cornell box camera sits at
  +z looking toward -z: the red wall (x = -1) is on the image's left, the green wall (x = +1) on its right.
* Every emitting mesh has ``vn`` normals pointing toward the part of the scene it lights (area
  emitters emit on the side of the shading normal).  Closed meshes (spheres, boxes) have outward
  normals, except the furnace cube whose normals point inward.
* ``distantdisk``: local +z (mapped by toWorld) is the direction *toward* the light.
  ``distant``: ``direction`` is the direction in which the light travels.
"""
import argparse
import math
import os
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SEED = 20240611

# --------------------------------------------------------------------------------------------------
# number formatting


def fnum(x):
    """Fixed, short float formatting for XML values (no '-0')."""
    s = "%.6g" % (float(x) + 0.0)
    if s == "-0":
        s = "0"
    return s


def fvec(v):
    return ", ".join(fnum(x) for x in v)


def normalize(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


# --------------------------------------------------------------------------------------------------
# tiny XML writer (attribute order is fixed by construction)


class Node:
    def __init__(self, tag, attrs=(), children=(), comment=None):
        self.tag = tag
        self.attrs = list(attrs)
        self.children = [c for c in children if c is not None]
        self.comment = comment

    def render(self, indent=0):
        pad = "    " * indent
        out = []
        if self.comment:
            out.append(pad + "<!-- " + self.comment + " -->")
        a = "".join(' %s="%s"' % (k, v) for k, v in self.attrs)
        if self.children:
            out.append("%s<%s%s>" % (pad, self.tag, a))
            for c in self.children:
                out.extend(c.render(indent + 1))
            out.append("%s</%s>" % (pad, self.tag))
        else:
            out.append("%s<%s%s/>" % (pad, self.tag, a))
        return out


def obj_(tag, type_, *children, comment=None):
    return Node(tag, [("type", type_)], children, comment)


def p_float(name, v):
    return Node("float", [("name", name), ("value", fnum(v))])


def p_int(name, v):
    return Node("integer", [("name", name), ("value", "%d" % v)])


def p_str(name, v):
    return Node("string", [("name", name), ("value", v)])


def p_bool(name, v):
    return Node("boolean", [("name", name), ("value", "true" if v else "false")])


def p_point(name, v):
    return Node("point", [("name", name), ("value", fvec(v))])


def p_vector(name, v):
    return Node("vector", [("name", name), ("value", fvec(v))])


def p_color(name, v):
    if np.isscalar(v):
        v = (v, v, v)
    return Node("color", [("name", name), ("value", fvec(v))])


def t_translate(v):
    return Node("translate", [("value", fvec(v))])


def t_scale(v):
    if np.isscalar(v):
        v = (v, v, v)
    return Node("scale", [("value", fvec(v))])


def t_rotate(axis, angle):
    return Node("rotate", [("axis", fvec(axis)), ("angle", fnum(angle))])


def t_lookat(origin, target, up):
    return Node("lookat", [("origin", fvec(origin)), ("target", fvec(target)), ("up", fvec(up))])


def p_transform(name, *ops):
    return Node("transform", [("name", name)], ops)


def write_xml(path, description, root):
    """`description`: list of comment lines (what the scene shows, what a correct image looks like)."""
    for line in description:
        assert "--" not in line, line
    lines = ['<?xml version="1.0" encoding="utf-8"?>', "<!--"]
    lines += ["    " + l if l else "" for l in description]
    lines += ["-->"]
    lines += root.render(0)
    write_text(path, "\n".join(lines) + "\n")


# --------------------------------------------------------------------------------------------------
# files

WRITTEN = []


def write_bytes(path, data):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as f:
        f.write(data)
    WRITTEN.append(path)


def write_text(path, text):
    write_bytes(path, text.encode("utf-8"))


def obj_text(V, N, F, header):
    """OBJ with v, vn and faces 'f a//a b//b c//c' (1-based; normals indexed like positions)."""
    out = ["# " + h for h in header]
    out += ["v %.6f %.6f %.6f" % tuple(float(x) + 0.0 for x in p) for p in V]
    if N is not None:
        out += ["vn %.6f %.6f %.6f" % tuple(float(x) + 0.0 for x in n) for n in N]
        out += ["f %d//%d %d//%d %d//%d" % (a + 1, a + 1, b + 1, b + 1, c + 1, c + 1) for a, b, c in F]
    else:
        out += ["f %d %d %d" % (a + 1, b + 1, c + 1) for a, b, c in F]
    return "\n".join(out) + "\n"


def write_obj(path, V, N, F, header=("generated by clrender scenes/build.py",)):
    write_text(path, obj_text(V, N, F, header))


def write_ply(path, V, N, F, comment="generated by clrender scenes/build.py"):
    """Binary little-endian PLY: float32 x y z nx ny nz; faces uchar count + int32 indices."""
    V = np.asarray(V, dtype="<f4")
    N = np.asarray(N, dtype="<f4")
    F = np.asarray(F, dtype="<i4")
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment %s\n"
        "element vertex %d\nproperty float x\nproperty float y\nproperty float z\n"
        "property float nx\nproperty float ny\nproperty float nz\n"
        "element face %d\nproperty list uchar int vertex_indices\nend_header\n"
        % (comment, len(V), len(F))
    )
    vert = np.empty(len(V), dtype=[("p", "<f4", (3,)), ("n", "<f4", (3,))])
    vert["p"] = V
    vert["n"] = N
    face = np.empty(len(F), dtype=[("c", "u1"), ("i", "<i4", (3,))])
    face["c"] = 3
    face["i"] = F
    assert face.dtype.itemsize == 13 and vert.dtype.itemsize == 24
    write_bytes(path, header.encode("ascii") + vert.tobytes() + face.tobytes())


# --------------------------------------------------------------------------------------------------
# geometry


def quad(p0, p1, p2, p3, normal):
    """A planar quad (corners in order around the boundary) as 2 triangles, with vn = normal and
    a winding that agrees with it."""
    V = np.array([p0, p1, p2, p3], dtype=np.float64)
    n = normalize(normal)
    if np.dot(np.cross(V[1] - V[0], V[2] - V[0]), n) < 0:
        V = V[::-1].copy()
    N = np.tile(n, (4, 1))
    F = np.array([[0, 1, 2], [0, 2, 3]])
    return V, N, F


def rect_xz(x0, x1, z0, z1, y, up=True):
    """Horizontal rectangle at height y, normal +y (up=True) or -y."""
    return quad((x0, y, z0), (x1, y, z0), (x1, y, z1), (x0, y, z1), (0, 1 if up else -1, 0))


def rot_y(deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def box(center, half, rot_y_deg=0.0, inward=False):
    """Axis-aligned box (optionally rotated about +y), 6 faces with flat per-face normals
    (24 vertices, 12 triangles); normals outward unless inward=True."""
    R = rot_y(rot_y_deg)
    hx, hy, hz = half
    Vs, Ns, Fs = [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = np.zeros(3)
            n[axis] = sign
            u = np.zeros(3)
            u[(axis + 1) % 3] = 1.0
            w = np.zeros(3)
            w[(axis + 2) % 3] = 1.0
            h = np.array(half)
            c = n * h[axis]
            du, dw = u * h[(axis + 1) % 3], w * h[(axis + 2) % 3]
            corners = [c - du - dw, c + du - dw, c + du + dw, c - du + dw]
            V, N, F = quad(*corners, -n if inward else n)
            Fs.append(F + 4 * len(Vs))
            Vs.append(V)
            Ns.append(N)
    V = np.concatenate(Vs) @ R.T + np.asarray(center, dtype=np.float64)
    N = np.concatenate(Ns) @ R.T
    return V, N, np.concatenate(Fs)


def icosahedron():
    t = (1.0 + math.sqrt(5.0)) / 2.0
    V = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]],
        dtype=np.float64,
    )
    F = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]],
        dtype=np.int64,
    )
    return V, F


def geodesic_sphere(n):
    """Unit sphere: each icosahedron face split into n*n triangles (20 n^2 triangles,
    10 n^2 + 2 vertices), projected onto the sphere; outward winding.  Returns (V, F)."""
    IV, IF = icosahedron()
    # local grid of one face: point (i, j), 0 <= j <= i <= n, barycentric weights (n-i, i-j, j)
    ii, jj = [], []
    for i in range(n + 1):
        for j in range(i + 1):
            ii.append(i)
            jj.append(j)
    ii = np.array(ii)
    jj = np.array(jj)
    M = len(ii)
    lid = {}
    for k in range(M):
        lid[(ii[k], jj[k])] = k
    tris = []
    for i in range(n):
        for j in range(i + 1):
            tris.append((lid[(i, j)], lid[(i + 1, j)], lid[(i + 1, j + 1)]))
            if j < i:
                tris.append((lid[(i, j)], lid[(i + 1, j + 1)], lid[(i, j + 1)]))
    tris = np.array(tris, dtype=np.int64)
    assert len(tris) == n * n

    W = np.stack([n - ii, ii - jj, jj], axis=1)  # (M, 3)
    corners = np.broadcast_to(IF[:, None, :], (20, M, 3)).copy()  # (20, M, 3)
    weights = np.broadcast_to(W[None], (20, M, 3)).copy()
    corners[weights == 0] = 15
    order = np.argsort(corners, axis=2, kind="stable")
    c = np.take_along_axis(corners, order, 2).reshape(-1, 3)
    w = np.take_along_axis(weights, order, 2).reshape(-1, 3)
    key = (((((c[:, 0] * 4096 + w[:, 0]) * 16 + c[:, 1]) * 4096 + w[:, 1]) * 16 + c[:, 2]) * 4096
           + w[:, 2])
    uniq, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    cc = c[first]
    ww = w[first].astype(np.float64)
    IVp = np.zeros((16, 3))  # corner index 15 = 'no corner' (weight 0)
    IVp[:12] = IV
    P = (IVp[cc[:, 0]] * ww[:, 0:1] + IVp[cc[:, 1]] * ww[:, 1:2] + IVp[cc[:, 2]] * ww[:, 2:3]) / n
    P /= np.linalg.norm(P, axis=1, keepdims=True)
    F = inverse.reshape(20, M)[:, tris].reshape(-1, 3)
    # consistent outward winding
    fn = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
    flip = np.einsum("ij,ij->i", fn, P[F[:, 0]] + P[F[:, 1]] + P[F[:, 2]]) < 0
    F[flip] = F[flip][:, ::-1]
    assert len(P) == 10 * n * n + 2 and len(F) == 20 * n * n
    return P, F


def vertex_normals(V, F):
    """Area-weighted vertex normals (deterministic: bincount sums in index order)."""
    fn = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N = np.zeros_like(V)
    for k in range(3):
        for a in range(3):
            N[:, a] += np.bincount(F[:, k], weights=fn[:, a], minlength=len(V))
    return N / np.linalg.norm(N, axis=1, keepdims=True)


def blob_displacement(P, rng_seed=SEED):
    """Radius of the 'blob' along unit directions P: 1 + a sum of seeded sinusoids."""
    rng = np.random.default_rng(rng_seed)
    r = np.ones(len(P))
    for amp, freq in ((0.06, 2.5), (0.035, 5.0), (0.02, 9.0), (0.012, 17.0), (0.007, 31.0),
                      (0.004, 53.0)):
        for _ in range(2):
            d = normalize(rng.normal(size=3))
            phase = rng.uniform(0, 2 * math.pi)
            r += amp * np.sin(freq * (P @ d) + phase)
    return r


def blob(n):
    P, F = geodesic_sphere(n)
    V = P * blob_displacement(P)[:, None]
    return V, vertex_normals(V, F), F


# --------------------------------------------------------------------------------------------------
# camera model (Nori's perspective camera) for numerical sanity checks


def camera_to_world(cam):
    """The camera's toWorld as clrender computes a <lookat> (one camera model, not a copy)."""
    from clrender.scene.transform import Transform

    return np.array(Transform.lookat(cam["origin"], cam["target"], cam["up"]).matrix)


def project(cam, pts):
    """World points -> pixel coordinates (x right, y down) with upstream Nori's perspective camera
    (camera-space +x maps to the image's left: sx = (1 - x/(z tan))/2). Returns (px, py, z_cam)."""
    W, H = cam["width"], cam["height"]
    inv = np.linalg.inv(camera_to_world(cam))
    p = np.c_[np.asarray(pts, float), np.ones(len(pts))] @ inv.T
    t = math.tan(math.radians(cam["fov"]) / 2)
    aspect = W / H
    xn = p[:, 0] / (p[:, 2] * t)
    yn = p[:, 1] / (p[:, 2] * t)
    sx = 0.5 * (1.0 - xn)
    sy = 0.5 - 0.5 * aspect * yn
    return sx * W, sy * H, p[:, 2]


def camera_node(cam, rfilter=None):
    return obj_(
        "camera", "perspective",
        p_float("fov", cam["fov"]),
        p_int("width", cam["width"]),
        p_int("height", cam["height"]),
        p_transform("toWorld", t_lookat(cam["origin"], cam["target"], cam["up"])),
        obj_("rfilter", rfilter) if rfilter else None,
    )


def sampler_node(spp):
    return obj_("sampler", "independent", p_int("sampleCount", spp))


def integrator_node(name, **kw):
    props = []
    if name == "av":
        props.append(p_float("length", kw.get("length", 1.0)))
    return obj_("integrator", name, *props)


def diffuse(albedo):
    return obj_("bsdf", "diffuse", p_color("albedo", albedo))


def microfacet(alpha, kd, int_ior=None):
    props = [p_float("alpha", alpha)]
    if int_ior is not None:
        props.append(p_float("intIOR", int_ior))
    props.append(p_color("kd", kd))
    return obj_("bsdf", "microfacet", *props)


def dielectric(int_ior=1.5, ext_ior=1.0):
    return obj_("bsdf", "dielectric", p_float("intIOR", int_ior), p_float("extIOR", ext_ior))


def mesh_obj(filename, *children, to_world=None, comment=None):
    props = [p_str("filename", filename)]
    if to_world is not None:
        props.append(to_world)
    return obj_("mesh", "obj", *props, *children, comment=comment)


def mesh_ply(filename, *children, to_world=None, comment=None):
    props = [p_str("filename", filename)]
    if to_world is not None:
        props.append(to_world)
    return obj_("mesh", "ply", *props, *children, comment=comment)


def sphere(center, radius, *children, comment=None):
    return obj_("mesh", "sphere", p_point("center", center), p_float("radius", radius), *children,
                comment=comment)


def area(radiance):
    return obj_("emitter", "area", p_color("radiance", radiance))


def rotation_to(d):
    """(axis, angle_deg) of the right-handed rotation taking +z to unit vector d."""
    z = np.array([0.0, 0.0, 1.0])
    d = normalize(d)
    axis = np.cross(z, d)
    s = np.linalg.norm(axis)
    angle = math.degrees(math.atan2(s, d[2]))
    if s < 1e-12:
        axis = np.array([1.0, 0.0, 0.0])
    return normalize(axis), angle


def rodrigues(axis, angle_deg):
    a = normalize(axis)
    th = math.radians(angle_deg)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K


def round_vec(v, nd=4):
    return tuple(round(float(x), nd) + 0.0 for x in v)


# --------------------------------------------------------------------------------------------------
# shared meshes

SPHERE_N = 14  # 20*14^2 = 3920 triangles


def build_shared(out):
    P, F = geodesic_sphere(SPHERE_N)
    write_obj(out / "meshes" / "unit_sphere.obj", P, P, F,
              ("generated by clrender scenes/build.py",
               "unit geodesic sphere, %d triangles, outward smooth vertex normals" % len(F)))


# --------------------------------------------------------------------------------------------------
# 1. Cornell box

CBOX_CAM = dict(origin=(0, 1, 4.0), target=(0, 1, 0), up=(0, 1, 0), fov=40, width=256, height=256)
CBOX_LIGHT = (0.5, 1.98)  # side, height
CBOX_WHITE = (0.725, 0.71, 0.68)
CBOX_RED = (0.63, 0.065, 0.05)
CBOX_GREEN = (0.14, 0.45, 0.091)
CBOX_LIGHT_RADIANCE = (17, 17, 17)
CBOX_MIRROR = ((-0.45, 0.35, -0.35), 0.35)
CBOX_GLASS = ((0.45, 0.35, 0.3), 0.35)


def cornell_meshes():
    s, h = CBOX_LIGHT
    return {
        "floor": rect_xz(-1, 1, -1, 1, 0.0, up=True),
        "ceiling": rect_xz(-1, 1, -1, 1, 2.0, up=False),
        "back": quad((-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1), (0, 0, 1)),
        "left": quad((-1, 0, -1), (-1, 0, 1), (-1, 2, 1), (-1, 2, -1), (1, 0, 0)),
        "right": quad((1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1), (-1, 0, 0)),
        "light": rect_xz(-s / 2, s / 2, -s / 2, s / 2, h, up=False),
    }


CBOX_SPP = {"normals": 4, "av": 32, "ao": 32, "direct_ems": 32, "direct_mats": 32, "direct_mis": 32,
            "whitted": 32, "path_mats": 64, "path_ems": 64, "path_mis": 64}

CBOX_EXPECT = {
    "normals": "|shading normal| as colour: floor and ceiling green (0,1,0), back wall blue (0,0,1), side "
               "walls red (1,0,0), light quad green; the spheres show smooth gradients.",
    "av": "average visibility within length 0.5: white on open surfaces, darker toward the box's edges "
          "and corners and around the spheres' contact points.",
    "ao": "ambient occlusion: white in the open, soft darkening in the corners and under the spheres.",
    "direct_ems": "direct light only (emitter sampling): walls lit by the ceiling light, soft shadows of "
                  "the spheres on the floor; the ceiling is black (it only sees the back of the light); "
                  "both spheres (delta BSDFs) are black; the light quad is white.",
    "direct_mats": "direct light only (BSDF sampling): the walls converge to the direct_ems image but are "
                   "much noisier (small light); the ceiling is black; the spheres are black except where "
                   "the sampled mirror/glass direction sees the light (its reflection/refraction).",
    "direct_mis": "direct light only (MIS): the direct_mats image (spheres show only the light's "
                  "reflection/refraction) with low noise; walls identical to direct_ems.",
    "whitted": "direct light on the walls (ceiling black); the left sphere is a perfect mirror reflecting "
               "the lit room, the right sphere refracts it (an inverted view); the glass sphere casts an "
               "ordinary dark shadow (shadow rays do not pass through glass); no caustic, no indirect "
               "light.",
    "path_mats": "global illumination by BSDF sampling only: converges to the path_mis image; noisy, with "
                 "fireflies.",
    "path_ems": "global illumination by emitter sampling (Le counted only after delta bounces): converges "
                "to the path_mis image; the caustic under the glass sphere is noisy.",
    "path_mis": "global illumination with MIS: lit ceiling, colour bleeding (red on the left, green on the "
                "right), the mirror sphere reflects the room, the glass sphere refracts it and focuses a "
                "bright caustic onto the floor.",
}


def cornell_scene(integrator, mesh_prefix, spp=None):
    m = mesh_prefix
    cam = CBOX_CAM
    kw = {"length": 0.5} if integrator == "av" else {}
    children = [
        integrator_node(integrator, **kw),
        sampler_node(spp if spp is not None else CBOX_SPP[integrator]),
        camera_node(cam),
        mesh_obj(m + "floor.obj", diffuse(CBOX_WHITE)),
        mesh_obj(m + "ceiling.obj", diffuse(CBOX_WHITE)),
        mesh_obj(m + "back.obj", diffuse(CBOX_WHITE)),
        mesh_obj(m + "left.obj", diffuse(CBOX_RED), comment="left wall (x = -1, image left): red"),
        mesh_obj(m + "right.obj", diffuse(CBOX_GREEN), comment="right wall (x = +1, image right): green"),
        mesh_obj(m + "light.obj", diffuse(0.0), area(CBOX_LIGHT_RADIANCE),
                 comment="ceiling light, 0.5 x 0.5 at y = 1.98, normals pointing down (-y)"),
        sphere(*CBOX_MIRROR, obj_("bsdf", "mirror"), comment="mirror sphere (back left)"),
        sphere(*CBOX_GLASS, dielectric(1.5, 1.0), comment="glass sphere (front right)"),
    ]
    return Node("scene", (), children)


def cornell_description(integrator, default=False):
    lines = [
        ("clrender default scene: " if default else "") +
        "Cornell box (x in [-1,1], y in [0,2] (y up), z in [-1,1], open toward the camera at +z),",
        "integrator '%s'.  Red wall left, green wall right, white floor/ceiling/back wall," % integrator,
        "a 0.5 x 0.5 area light just below the ceiling (radiance 17), a mirror sphere (back left) and",
        "a glass sphere (front right), analytic spheres of radius 0.35.  256 x 256, fov 40.",
        "",
        "Correct image: " + CBOX_EXPECT[integrator],
    ]
    # wrap the expectation text
    out = []
    for l in lines:
        while len(l) > 100:
            k = l.rfind(" ", 0, 100)
            out.append(l[:k])
            l = "    " + l[k + 1:]
        out.append(l)
    return out


def build_cornell(out):
    d = out / "cornell"
    for name, (V, N, F) in cornell_meshes().items():
        write_obj(d / "meshes" / (name + ".obj"), V, N, F)
    for integ in CBOX_SPP:
        write_xml(d / ("cornell_%s.xml" % integ), cornell_description(integ),
                  cornell_scene(integ, "meshes/"))
    # default scenes (README render command)
    write_xml(out / "default.xml", cornell_description("path_mis", default=True),
              cornell_scene("path_mis", "cornell/meshes/", 64))
    write_xml(out / "default_normals.xml", cornell_description("normals", default=True),
              cornell_scene("normals", "cornell/meshes/", 4))


# --------------------------------------------------------------------------------------------------
# 2. Veach-style MIS scene

MIS_CAM = dict(origin=(0, 6.5, 12), target=(0, 2.75, 0), up=(0, 1, 0), fov=45, width=384, height=320)
MIS_LIGHT_Y, MIS_LIGHT_Z = 5.6, -3.4
MIS_LIGHT_X = (-3.75, -1.25, 1.25, 3.75)
MIS_RADII = (0.03, 0.1, 0.3, 0.9)
MIS_POWER_K = 8.0  # radiance = K / r^2  -> every light has power 4 pi^2 K
MIS_ALPHAS = (0.005, 0.02, 0.05, 0.2)  # plate 0 (back, top) .. plate 3 (front, bottom)
MIS_PLATE_CENTERS = ((0, 2.3, -1.6), (0, 1.6, -0.35), (0, 1.0, 0.9), (0, 0.5, 2.15))
MIS_PLATE_HALF = (4.0, 0.6)  # half width (x), half depth
MIS_AMBIENT = dict(center=(0, 9.0, 9.0), half=(6.0, 3.0), radiance=0.6)


def mis_plate(i):
    c = np.array(MIS_PLATE_CENTERS[i], float)
    eye = np.array(MIS_CAM["origin"], float)
    lc = np.array((0.0, MIS_LIGHT_Y, MIS_LIGHT_Z))
    n = normalize(normalize(eye - c) + normalize(lc - c))
    n = normalize(n - np.array([1.0, 0, 0]) * n[0])
    t = normalize(np.cross(np.array([1.0, 0, 0]), n))  # in the y-z plane, perpendicular to n
    hw, hd = MIS_PLATE_HALF
    ex = np.array([hw, 0, 0])
    corners = [c - ex - hd * t, c + ex - hd * t, c + ex + hd * t, c - ex + hd * t]
    return quad(*corners, n), c, n, t


def mis_lights():
    return [((x, MIS_LIGHT_Y, MIS_LIGHT_Z), r, MIS_POWER_K / r ** 2) for x, r in zip(MIS_LIGHT_X, MIS_RADII)]


def build_mis(out):
    d = out / "mis"
    for i in range(4):
        (V, N, F), *_ = mis_plate(i)
        write_obj(d / "meshes" / ("plate%d.obj" % i), V, N, F)
    write_obj(d / "meshes" / "floor.obj", *rect_xz(-12, 12, -8, 14, 0.0, up=True))
    write_obj(d / "meshes" / "back.obj",
              *quad((-12, 0, -8), (12, 0, -8), (12, 12, -8), (-12, 12, -8), (0, 0, 1)))
    a = MIS_AMBIENT
    (cx, cy, cz), (hx, hz) = a["center"], a["half"]
    write_obj(d / "meshes" / "ambient_light.obj", *rect_xz(cx - hx, cx + hx, cz - hz, cz + hz, cy, up=False))

    spp = {"direct_ems": 32, "direct_mats": 32, "direct_mis": 32, "path_mis": 64}
    expect = {
        "direct_ems": "emitter sampling only: highlights of the big lights on the shiny plates are very "
                      "noisy (the smooth top plate is mostly noise), the small lights on the rough bottom "
                      "plate look fine.",
        "direct_mats": "BSDF sampling only: the reflections of the small lights on the rough plates are "
                       "noisy speckles, while the smooth plates show clean reflections.",
        "direct_mis": "MIS: every highlight is clean; the expected image equals direct_ems and direct_mats.",
        "path_mis": "global illumination with MIS: like direct_mis plus interreflection; highlights clean.",
    }
    for integ, n in spp.items():
        desc = [
            "Veach-style multiple importance sampling scene, integrator '%s'." % integ,
            "Four plates (microfacet, kd 0.02, alpha 0.005, 0.02, 0.05, 0.2 from the back/top plate to",
            "the front/bottom plate) each reflect four spherical area lights (tessellated spheres with",
            "outward normals) of radius 0.03, 0.1, 0.3, 0.9 (left to right in the image) and EQUAL power:",
            "radiance = 8 / r^2.  Each plate is tilted so the lights' mirror images fall on it: every",
            "plate shows a row of four highlights, small and sharp on the smooth plates, wide on the",
            "rough ones.  A dim large area light above/behind the camera (radiance 0.6) and a grey floor",
            "and back wall keep the background from being black.  384 x 320, fov 45.",
            "",
            "Correct image: " + expect[integ][:80],
        ]
        rest = expect[integ][80:]
        while rest:
            k = rest.rfind(" ", 0, 90) if len(rest) > 90 else len(rest)
            desc.append("    " + rest[:k].strip())
            rest = rest[k:].strip()
        children = [integrator_node(integ), sampler_node(n), camera_node(MIS_CAM),
                    mesh_obj("meshes/floor.obj", diffuse(0.3)),
                    mesh_obj("meshes/back.obj", diffuse(0.3)),
                    mesh_obj("meshes/ambient_light.obj", diffuse(0.0), area(MIS_AMBIENT["radiance"]),
                             comment="dim ambient light above/behind the camera, normals -y")]
        for i in range(4):
            children.append(mesh_obj("meshes/plate%d.obj" % i, microfacet(MIS_ALPHAS[i], 0.02),
                                     comment="plate %d, alpha %g" % (i, MIS_ALPHAS[i])))
        for (c, r, L) in mis_lights():
            children.append(mesh_obj(
                "../meshes/unit_sphere.obj", diffuse(0.0), area(L),
                to_world=p_transform("toWorld", t_scale(r), t_translate(c)),
                comment="spherical light r = %g, radiance %s (power %s)" % (r, fnum(L),
                                                                          fnum(4 * math.pi ** 2 * r * r * L))))
        write_xml(d / ("mis_%s.xml" % integ), desc, Node("scene", (), children))


# --------------------------------------------------------------------------------------------------
# 3. Delta lights

DELTA_CAM = dict(origin=(0, 2.6, 7.5), target=(0, 0.5, 0), up=(0, 1, 0), fov=40, width=320, height=240)
DELTA_POINTS = (((-2.5, 3.5, 2.0), (120, 100, 80)), ((2.5, 2.5, 1.5), (40, 60, 90)))
DELTA_DISTANT = dict(direction=(0.4, -1.0, -0.5), irradiance=(1.0, 0.95, 0.85))
DELTA_CUBE = dict(center=(-1.4, 0.5, -0.2), half=(0.5, 0.5, 0.5), rot=30.0)
DELTA_SPHERE_A = ((0.2, 0.65, 0.4), 0.65)
DELTA_SPHERE_T = ((1.8, 0.45, -0.5), 0.45)


def build_delta(out):
    d = out / "delta"
    write_obj(d / "meshes" / "ground.obj", *rect_xz(-8, 8, -8, 8, 0.0, up=True))
    c = DELTA_CUBE
    write_obj(d / "meshes" / "cube.obj", *box(c["center"], c["half"], c["rot"]))
    variants = {
        "direct_ems": (16, True, "direct illumination from two point lights (warm left, cool right) and "
                                 "a distant light (from above, front left, shadows toward the back right): sharp "
                                 "shadows, three shadows per object; sharp highlight on the analytic "
                                 "sphere, broader on the rough blue sphere."),
        "path_mis": (64, True, "the direct_ems image plus indirect light (shadows are not pitch black, "
                               "slight colour bleeding from the red cube onto the ground)."),
        "direct": (16, False, "Nori's 'direct' integrator (point lights only, no distant light): two "
                              "sharp shadows per object; regions seen by neither point light are black."),
    }
    for integ, (spp, with_distant, expect) in variants.items():
        desc = ["Delta lights, integrator '%s'.  A ground plane (diffuse 0.5), a red diffuse cube (left)," % integ,
                "a glossy analytic sphere (microfacet alpha 0.08, middle) and a rough blue tessellated",
                "sphere (microfacet alpha 0.3, right).  Point lights: warm at (-2.5, 3.5, 2), power",
                "(120, 100, 80); cool at (2.5, 2.5, 1.5), power (40, 60, 90)." +
                ("  Distant light: direction" if with_distant else ""),
                ("(0.4, -1, -0.5) (travel direction, normalised by the loader), irradiance (1, 0.95, 0.85)."
                 if with_distant else "No distant light in this variant."),
                "320 x 240, fov 40.", "",
                "Correct image: " + expect[:80]]
        rest = expect[80:]
        while rest:
            k = rest.rfind(" ", 0, 90) if len(rest) > 90 else len(rest)
            desc.append("    " + rest[:k].strip())
            rest = rest[k:].strip()
        children = [integrator_node(integ), sampler_node(spp), camera_node(DELTA_CAM),
                    mesh_obj("meshes/ground.obj", diffuse(0.5)),
                    mesh_obj("meshes/cube.obj", diffuse((0.7, 0.15, 0.1))),
                    sphere(*DELTA_SPHERE_A, microfacet(0.08, (0.2, 0.4, 0.2))),
                    mesh_obj("../meshes/unit_sphere.obj", microfacet(0.3, (0.1, 0.2, 0.6)),
                             to_world=p_transform("toWorld", t_scale(DELTA_SPHERE_T[1]),
                                                  t_translate(DELTA_SPHERE_T[0])))]
        for pos, power in DELTA_POINTS:
            children.append(obj_("emitter", "point", p_point("position", pos), p_color("power", power)))
        if with_distant:
            children.append(obj_("emitter", "distant", p_vector("direction", DELTA_DISTANT["direction"]),
                                 p_color("irradiance", DELTA_DISTANT["irradiance"])))
        write_xml(d / ("delta_%s.xml" % integ), desc, Node("scene", (), children))


# --------------------------------------------------------------------------------------------------
# 4. Glass / caustics

GLASS_CAM = dict(origin=(0, 2.2, 5.5), target=(0, 0.4, 0), up=(0, 1, 0), fov=40, width=320, height=240)
GLASS_LIGHT = dict(center=(-0.4, 3.0, 0.6), half=0.2, radiance=120)
GLASS_SPHERE = ((-0.75, 0.5, 0.0), 0.5)
GLASS_SLAB = dict(center=(0.85, 0.15, 0.25), half=(0.6, 0.15, 0.4), rot=-25.0)


def build_glass(out):
    d = out / "glass"
    write_obj(d / "meshes" / "floor.obj", *rect_xz(-6, 6, -3, 6, 0.0, up=True))
    write_obj(d / "meshes" / "back.obj", *quad((-6, 0, -3), (6, 0, -3), (6, 6, -3), (-6, 6, -3), (0, 0, 1)))
    s = GLASS_SLAB
    write_obj(d / "meshes" / "slab.obj", *box(s["center"], s["half"], s["rot"]))
    g = GLASS_LIGHT
    (cx, cy, cz), h = g["center"], g["half"]
    write_obj(d / "meshes" / "light.obj", *rect_xz(cx - h, cx + h, cz - h, cz + h, cy, up=False))
    for integ, spp, expect in (
            ("path_mis", 256, "a glass sphere (left) and a glass slab (right, box with outward normals) "
                              "on a light floor; the sphere focuses the light into a bright caustic on "
                              "the floor just behind/right of its contact point, the slab casts a "
                              "lighter-edged shadow with caustic fringes; the scene is otherwise dim."),
            ("path_mats", 256, "same expected image as glass_path_mis but far noisier (the 0.4 x 0.4 "
                               "light is only found by BSDF sampling); caustics converge cleaner than "
                               "the directly lit floor.")):
        desc = ["Glass and caustics, integrator '%s'.  Diffuse floor (0.6) and back wall (0.5)," % integ,
                "a dielectric sphere (intIOR 1.5, radius 0.5) and a dielectric slab (1.2 x 0.3 x 0.8),",
                "lit by a small 0.4 x 0.4 area light at y = 3 (normals down, radiance 120).",
                "320 x 240, fov 40.", "", "Correct image: " + expect[:80]]
        rest = expect[80:]
        while rest:
            k = rest.rfind(" ", 0, 90) if len(rest) > 90 else len(rest)
            desc.append("    " + rest[:k].strip())
            rest = rest[k:].strip()
        children = [integrator_node(integ), sampler_node(spp), camera_node(GLASS_CAM),
                    mesh_obj("meshes/floor.obj", diffuse(0.6)),
                    mesh_obj("meshes/back.obj", diffuse(0.5)),
                    sphere(*GLASS_SPHERE, dielectric(1.5, 1.0)),
                    mesh_obj("meshes/slab.obj", dielectric(1.5, 1.0)),
                    mesh_obj("meshes/light.obj", diffuse(0.0), area(g["radiance"]))]
        write_xml(d / ("glass_%s.xml" % integ), desc, Node("scene", (), children))


# --------------------------------------------------------------------------------------------------
# 5. Furnace

FURNACE_RHO, FURNACE_LE = 0.5, 1.0
FURNACE_CAM = dict(origin=(0.1, -0.2, 0.3), target=(0.6, 0.1, -1.0), up=(0, 1, 0), fov=70, width=64, height=64)
ENV_CAM = dict(origin=(0, 0, 4), target=(0, 0, 0), up=(0, 1, 0), fov=40, width=64, height=64)
ENV_RHO = 0.8


def build_furnace(out):
    d = out / "furnace"
    write_obj(d / "meshes" / "cube_inward.obj", *box((0, 0, 0), (1, 1, 1), 0.0, inward=True))
    rho, le = FURNACE_RHO, FURNACE_LE
    path_val = le / (1 - rho)
    direct_val = le * (1 + rho)
    for integ in ("path_mis", "path_ems", "path_mats", "direct_mis", "direct_ems", "direct_mats"):
        val = path_val if integ.startswith("path") else direct_val
        spp = 64
        desc = ["Furnace test, integrator '%s'.  The camera is inside a closed cube [-1,1]^3 whose six" % integ,
                "walls (one OBJ, normals pointing INTO the cube) are diffuse with albedo rho = %g and" % rho,
                "emit area radiance Le = %g.  Analytic answer, identical in every pixel:" % le,
                "path integrators (infinite depth) converge to Le / (1 - rho) = %g;" % path_val,
                "direct integrators give Le (1 + rho) = %g.  This file: expect %g (grey, uniform)." % (direct_val, val),
                "64 x 64, fov 70, box filter.", "",
                "Correct image: uniform grey of value %g in every pixel.  Any structure (edges, corners," % val,
                "gradients) is a bug."]
        children = [integrator_node(integ), sampler_node(spp), camera_node(FURNACE_CAM, rfilter="box"),
                    mesh_obj("meshes/cube_inward.obj", diffuse(rho), area(le))]
        write_xml(d / ("furnace_%s.xml" % integ), desc, Node("scene", (), children))
    for integ in ("path_mis", "direct_mis"):
        desc = ["Environment furnace test, integrator '%s'.  An analytic diffuse sphere (albedo %g, radius 1)" % (integ, ENV_RHO),
                "under a constant environment (extension) of radiance 1.  A convex object sees the whole",
                "environment over every hemisphere and never itself, so direct and path integrators",
                "both converge to exactly %g on the sphere and 1 on the background.  64 x 64, fov 40, box filter." % ENV_RHO,
                "", "Correct image: a flat disc of value %g on a uniform background of 1 (no limb darkening," % ENV_RHO,
                "no shading at all)."]
        children = [integrator_node(integ), sampler_node(64), camera_node(ENV_CAM, rfilter="box"),
                    sphere((0, 0, 0), 1.0, diffuse(ENV_RHO)),
                    obj_("emitter", "constant", p_color("radiance", 1.0))]
        write_xml(d / ("furnace_env_%s.xml" % integ), desc, Node("scene", (), children))


# --------------------------------------------------------------------------------------------------
# 6. Large mesh

BLOB_N_LARGE = 224  # 20 * 224^2 = 1,003,520 triangles
BLOB_N_SMALL = 71   # 20 * 71^2 = 100,820 triangles
LARGE_CAM = dict(origin=(0.0, 2.6, 6.5), target=(0, 1.0, 0), up=(0, 1, 0), fov=40, width=320, height=240)
LARGE_SUN_DIR = (-0.5, 0.8, 0.35)  # toward the sun
LARGE_LIGHT = dict(center=(1.5, 3.5, 1.5), half=0.5, radiance=6)


BLOBS = (("1m", BLOB_N_LARGE), ("100k", BLOB_N_SMALL))
# Lowest vertex of each blob below its centre, to 3 decimals (what the XML needs; asserted when meshes are built).
BLOB_LIFT = {"1m": 0.995, "100k": 0.995}


def blob_ply_size(n):
    """(vertices, faces) of the blob with subdivision n (checked before reusing a generated file)."""
    nf = 20 * n * n
    nv = 10 * n * n + 2
    return nv, nf


def write_blob(path, n):
    V, N, F = blob(n)
    lift = -float(V[:, 1].min())
    assert abs(lift - BLOB_LIFT[{BLOB_N_LARGE: "1m", BLOB_N_SMALL: "100k"}[n]]) < 6e-4, lift
    write_ply(path, V, N, F, comment="clrender scenes/build.py: displaced geodesic sphere, %d triangles" % len(F))


def ensure_large_meshes(out=HERE, force=False):
    """Generate the large blob PLYs under out/largemesh/meshes unless a complete one is already there
    (they are tens of MB, so they are generated on demand rather than kept in git). Returns the paths."""
    paths = []
    for tag, n in BLOBS:
        p = Path(out) / "largemesh" / "meshes" / ("blob_%s.ply" % tag)
        paths.append(p)
        if not force and p.is_file():
            nv, nf = blob_ply_size(n)
            with open(p, "rb") as f:
                head = f.read(512)
            if (b"element vertex %d\n" % nv) in head and (b"element face %d\n" % nf) in head:
                end = head.index(b"end_header\n") + len(b"end_header\n")
                if p.stat().st_size == end + 24 * nv + 13 * nf:
                    continue
        p.parent.mkdir(parents=True, exist_ok=True)
        tmp = p.with_name(p.name + ".tmp")
        write_blob(tmp, n)
        WRITTEN.pop()
        os.replace(tmp, p)
    return paths


def build_large(out, meshes=True):
    d = out / "largemesh"
    lift = dict(BLOB_LIFT)
    for tag, n in BLOBS:
        if meshes:
            write_blob(d / "meshes" / ("blob_%s.ply" % tag), n)
        # quoted by clrender's error when the PLY is missing (clrender/shapes/meshfile.py)
        write_text(d / "meshes" / ("blob_%s.ply.missing" % tag),
                   "generated, not kept in git: make it with 'python scenes/build.py --large-meshes' in the clrender "
                   "checkout (or 'python scenes/build.py', which writes every scene)\n")
    write_obj(d / "meshes" / "ground.obj", *rect_xz(-10, 10, -10, 10, 0.0, up=True))
    g = LARGE_LIGHT
    (cx, cy, cz), h = g["center"], g["half"]
    write_obj(d / "meshes" / "light.obj", *rect_xz(cx - h, cx + h, cz - h, cz + h, cy, up=False))
    axis, angle = rotation_to(LARGE_SUN_DIR)

    def scene(integ, spp, tag):
        ly = round(lift[tag], 3) + 0.001  # rests on the ground (lowest vertex 1 mm above it)
        blob_mesh = mesh_ply("meshes/blob_%s.ply" % tag, microfacet(0.15, (0.45, 0.3, 0.2)),
                             to_world=p_transform("toWorld", t_translate((0, ly, 0))))
        return Node("scene", (), [
            integrator_node(integ), sampler_node(spp), camera_node(LARGE_CAM),
            mesh_obj("meshes/ground.obj", diffuse(0.5)),
            blob_mesh,
            mesh_obj("meshes/light.obj", diffuse(0.0), area(g["radiance"]),
                     comment="1 x 1 area light at y = 3.5, front right, normals down"),
            obj_("emitter", "distantdisk", p_color("radiance", 40), p_float("thetaA", 5),
                 p_transform("toWorld", t_rotate(round_vec(axis), round(angle, 4))),
                 comment="sun: cone of 5 degrees about local +z, rotated toward %s" % fvec(LARGE_SUN_DIR)),
        ])

    common = ["A lumpy 'blob' (geodesic sphere displaced along the normal by seeded sinusoids, radius",
              "about 1 +- 0.15, smooth float32 vertex normals, binary little-endian PLY) resting on a",
              "ground plane, lit by a distantdisk sun (thetaA 5, radiance 40, high up, from the left and",
              "slightly in front) and a 1 x 1 area light (front right, radiance 6).  320 x 240, fov 40.",
              "The blob PLYs are not kept in git: running python scenes/build.py generates them."]
    write_xml(d / "largemesh_normals.xml",
              ["Large mesh (1,003,520 triangles), integrator 'normals'."] + common +
              ["", "Correct image: a smooth, bumpy ball coloured by |normal| (green top, red/blue sides),",
               "ground green (0,1,0); no faceting, no holes, no black triangles."],
              scene("normals", 4, "1m"))
    write_xml(d / "largemesh_path_mis.xml",
              ["Large mesh (1,003,520 triangles), integrator 'path_mis'."] + common +
              ["", "Correct image: a brown glossy lumpy ball with a crisp sun shadow on the ground toward",
               "the back right and a soft second shadow toward the back left; smooth shading."],
              scene("path_mis", 64, "1m"))
    write_xml(d / "mesh100k_normals.xml",
              ["~100k-triangle mesh (100,820 triangles), integrator 'normals': the same blob at a lower",
               "resolution (same shape, same file layout)."] + common[1:] +
              ["", "Correct image: as largemesh_normals.xml (very nearly identical)."],
              scene("normals", 4, "100k"))


# --------------------------------------------------------------------------------------------------
# 7. Analytic spheres + distantdisk + constant environment

SUN_CAM = dict(origin=(0, 2.0, 7.0), target=(0, 0.5, 0), up=(0, 1, 0), fov=40, width=320, height=240)
SUN_DIR = (-0.45, 0.75, 0.5)  # toward the sun
SUN_SPHERES = (((-1.45, 0.6, 0.0), 0.6, "diffuse"), ((0.0, 0.6, 0.0), 0.6, "glossy"),
               ((1.45, 0.6, 0.0), 0.6, "rough"))


def build_sun(out):
    d = out / "sun"
    write_obj(d / "meshes" / "ground.obj", *rect_xz(-20, 20, -20, 20, 0.0, up=True))
    axis, angle = rotation_to(SUN_DIR)
    for integ, spp in (("path_mis", 64), ("direct_mis", 32)):
        desc = ["Analytic spheres under a sun and sky, integrator '%s'." % integ,
                "Three analytic spheres (mesh type 'sphere', radius 0.6) on a diffuse ground (0.5):",
                "left diffuse orange, middle glossy blue microfacet (alpha 0.05), right rough grey",
                "microfacet (alpha 0.3).  Light: a distantdisk sun (thetaA 6 degrees, radiance 50, toward",
                "the upper left in front of the spheres) and a constant bluish sky (extension, radiance",
                "(0.12, 0.15, 0.2)).  320 x 240, fov 40.", "",
                "Correct image: sky-blue background, sunlit spheres with crisp but slightly soft shadows",
                "cast toward the back right, a small bright sun highlight on the glossy sphere, a broad",
                "one on the rough sphere" + ("; indirect light brightens the shadows." if integ == "path_mis"
                                              else "; no interreflection (direct light only).")]
        bs = {"diffuse": diffuse((0.8, 0.35, 0.15)), "glossy": microfacet(0.05, (0.05, 0.1, 0.4)),
              "rough": microfacet(0.3, 0.3)}
        children = [integrator_node(integ), sampler_node(spp), camera_node(SUN_CAM),
                    mesh_obj("meshes/ground.obj", diffuse(0.5))]
        children += [sphere(c, r, bs[k]) for c, r, k in SUN_SPHERES]
        children += [
            obj_("emitter", "distantdisk", p_color("radiance", 50), p_float("thetaA", 6),
                 p_transform("toWorld", t_rotate(round_vec(axis), round(angle, 4))),
                 comment="sun: local +z rotated toward %s (the direction toward the sun)" % fvec(SUN_DIR)),
            obj_("emitter", "constant", p_color("radiance", (0.12, 0.15, 0.2))),
        ]
        write_xml(d / ("sun_%s.xml" % integ), desc, Node("scene", (), children))


# --------------------------------------------------------------------------------------------------
# checks (used by --check and tests/test_scenes_build.py)

def check_xml(path):
    """The file is what clrender reads: its own strict parser (tags, attributes, numbers), every plugin type
    known to clrender's registry, and every referenced file present."""
    from clrender import plugins  # noqa: F401  (registers every plugin)
    from clrender.scene.registry import lookup
    from clrender.scene.xmlparser import parse_file

    path = Path(path)
    spec = parse_file(str(path))
    assert spec.tag == "scene", path
    for s in spec.walk():
        if s.tag != "scene":
            lookup(s.tag, s.type, s.location, s.format)
        if s.props.has("filename"):
            assert Path(s.props.get_string("filename")).is_file(), (path, s.props.raw("filename"))
    return spec


def read_obj(path):
    V, N, F = [], [], []
    for line in Path(path).read_text().splitlines():
        p = line.split()
        if not p:
            continue
        if p[0] == "v":
            V.append([float(x) for x in p[1:4]])
        elif p[0] == "vn":
            N.append([float(x) for x in p[1:4]])
        elif p[0] == "f":
            F.append([int(x.split("/")[0]) - 1 for x in p[1:]])
    return np.array(V), (np.array(N) if N else None), np.array(F)


def sanity_checks(out):
    out = Path(out)
    for xml in sorted(out.rglob("*.xml")):
        check_xml(xml)

    def inside(cam, pts, margin=0.0):
        px, py, z = project(cam, np.array(pts, float))
        return bool(np.all(z > 0) and np.all(px >= -margin) and np.all(px <= cam["width"] + margin)
                    and np.all(py >= -margin) and np.all(py <= cam["height"] + margin))

    # Cornell: the box opening (front edges) and everything inside are in view; red wall on the left
    cam = CBOX_CAM
    assert inside(cam, [(-1, 0, 1), (1, 0, 1), (-1, 2, 1), (1, 2, 1), (-1, 0, -1), (1, 2, -1)])
    px, py, _ = project(cam, np.array([(-1, 1, 0), (1, 1, 0), (0, 0, 0), (0, 2, 0)], float))
    assert px[0] < cam["width"] / 2 < px[1], "red wall (x=-1) must be on the image's left"
    assert py[3] < cam["height"] / 2 < py[2], "ceiling above floor in the image"
    # spheres inside the box, not touching walls or each other
    for c, r in (CBOX_MIRROR, CBOX_GLASS):
        c = np.array(c)
        assert np.all(np.abs(c[[0, 2]]) + r < 1) and c[1] - r >= 0 and c[1] + r < CBOX_LIGHT[1]
    assert np.linalg.norm(np.subtract(CBOX_MIRROR[0], CBOX_GLASS[0])) > CBOX_MIRROR[1] + CBOX_GLASS[1]
    # wall normals point into the box, light normal down
    for name in ("floor", "ceiling", "back", "left", "right", "light"):
        V, N, F = read_obj(out / "cornell" / "meshes" / (name + ".obj"))
        to_center = np.array([0, 1, 0]) - V
        assert np.all(np.einsum("ij,ij->i", N, to_center) > 0), name
    # MIS: the mirror image of every light centre on every plate lies on that plate; view
    cam = MIS_CAM
    eye = np.array(cam["origin"], float)
    for i in range(4):
        (V, N, F), c, n, t = mis_plate(i)
        assert inside(cam, V, margin=0.02 * cam["width"]), ("plate", i)
        for (lc, r, L) in mis_lights():
            lc = np.array(lc)
            e2 = eye - 2 * np.dot(eye - c, n) * n  # reflected eye
            dd = lc - e2
            s = np.dot(c - e2, n) / np.dot(dd, n)
            hit = e2 + s * dd
            assert 0 < s < 1
            assert abs(hit[0]) < MIS_PLATE_HALF[0] and abs(np.dot(hit - c, t)) < MIS_PLATE_HALF[1], (i, lc)
    for (lc, r, L) in mis_lights():
        assert inside(cam, [np.add(lc, (sx * r, sy * r, 0)) for sx in (-1, 1) for sy in (-1, 1)]), lc
    # plates do not occlude each other along the view of their centres: image rows are ordered
    rows = [project(cam, np.array([mis_plate(i)[1]]))[1][0] for i in range(4)]
    assert rows == sorted(rows)
    # power equality
    powers = [4 * math.pi ** 2 * r * r * L for _, r, L in mis_lights()]
    assert max(powers) - min(powers) < 1e-9 * max(powers)
    # delta / glass / sun / large-mesh cameras see their objects
    assert inside(DELTA_CAM, [DELTA_CUBE["center"], DELTA_SPHERE_A[0], DELTA_SPHERE_T[0]])
    assert inside(GLASS_CAM, [GLASS_SPHERE[0], GLASS_SLAB["center"]])
    assert inside(SUN_CAM, [np.add(c, (sx * r, 0, 0)) for c, r, _ in SUN_SPHERES for sx in (-1, 1)])
    assert inside(LARGE_CAM, [(-1.25, 0, 0), (1.25, 0, 0), (0, 2.3, 0), (-1.25, 2.3, 0), (1.25, 2.3, 0)])
    # rotations: +z goes to the sun directions, which are above the horizon
    for dvec in (SUN_DIR, LARGE_SUN_DIR):
        axis, angle = rotation_to(dvec)
        z = rodrigues(round_vec(axis), round(angle, 4)) @ np.array([0, 0, 1.0])
        assert np.allclose(z, normalize(dvec), atol=1e-4) and z[1] > 0
    # furnace: camera inside the cube; inward normals
    assert np.all(np.abs(FURNACE_CAM["origin"]) < 1)
    V, N, F = read_obj(out / "furnace" / "meshes" / "cube_inward.obj")
    assert np.all(np.einsum("ij,ij->i", N, -V) > 0)
    # glass slab / delta cube / unit sphere: outward normals, winding agrees with normals
    for p, cen in ((out / "glass" / "meshes" / "slab.obj", GLASS_SLAB["center"]),
                   (out / "delta" / "meshes" / "cube.obj", DELTA_CUBE["center"]),
                   (out / "meshes" / "unit_sphere.obj", (0, 0, 0))):
        V, N, F = read_obj(p)
        assert np.all(np.einsum("ij,ij->i", N, V - np.array(cen)) > 0), p
        fn = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
        assert np.all(np.einsum("ij,ij->i", fn, N[F[:, 0]]) > 0), p
    # ground-resting objects
    for c, r, _ in SUN_SPHERES:
        assert abs(c[1] - r) < 1e-9
    return True


# --------------------------------------------------------------------------------------------------


# --------------------------------------------------------------------------------------------------
# 8. A Mitsuba 3 scene (read by the Mitsuba reader: rough metal and glass, plastic with a texture, a blend,
#    parametric shapes, a spot and a disk light under a constant sky). Mitsuba renders the same file.

MITSUBA_SHOWCASE = """<?xml version="1.0" encoding="utf-8"?>
<!-- generated by clrender scenes/build.py: a Mitsuba 3 scene; `clrender render` and Mitsuba 3 read it unchanged.
     Rough gold and copper (roughconductor), rough BK7 glass (roughdielectric), a textured roughplastic floor
     (checkerboard), a blendbsdf box, a dielectric sphere, a cylinder and a disk; lit by a disk area light, a spot
     and a constant sky.
     Correct image: a checkered floor in perspective under a blue-grey sky; a gold sphere on the left, a clear
     glass sphere in the middle front and a smooth one on the right, both casting bright caustics; a copper
     cylinder and a reddish half-metallic cube behind them. Mitsuba 3.9.1 renders image means within 0.1 %. -->
<scene version="3.0.0">
    <default name="spp" value="256"/>
    <default name="res" value="320"/>
    <integrator type="path">
        <integer name="max_depth" value="12"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="38"/>
        <transform name="to_world">
            <lookat origin="0, 2.2, 6.5" target="0, 0.55, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <rfilter type="gaussian"/>
        </film>
    </sensor>

    <emitter type="constant">
        <rgb name="radiance" value="0.25, 0.3, 0.4"/>
    </emitter>
    <emitter type="spot">
        <rgb name="intensity" value="40, 36, 30"/>
        <float name="cutoff_angle" value="25"/>
        <float name="beam_width" value="18"/>
        <transform name="to_world">
            <lookat origin="3, 4, 2" target="0, 0.4, 0" up="0, 1, 0"/>
        </transform>
    </emitter>
    <shape type="disk">
        <transform name="to_world">
            <scale value="0.9"/>
            <rotate x="1" angle="90"/>
            <translate x="-1.2" y="3.2" z="0.5"/>
        </transform>
        <emitter type="area">
            <rgb name="radiance" value="6, 6, 6"/>
        </emitter>
    </shape>

    <shape type="rectangle">
        <transform name="to_world">
            <scale value="4"/>
            <rotate x="1" angle="-90"/>
        </transform>
        <bsdf type="roughplastic">
            <float name="alpha" value="0.15"/>
            <texture type="checkerboard" name="diffuse_reflectance">
                <rgb name="color0" value="0.75, 0.75, 0.72"/>
                <rgb name="color1" value="0.15, 0.2, 0.3"/>
                <transform name="to_uv">
                    <scale x="8" y="8"/>
                </transform>
            </texture>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="-1.3, 0.55, 0.2"/>
        <float name="radius" value="0.55"/>
        <bsdf type="roughconductor">
            <string name="material" value="Au"/>
            <string name="distribution" value="ggx"/>
            <float name="alpha" value="0.18"/>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="0, 0.55, 0.9"/>
        <float name="radius" value="0.55"/>
        <bsdf type="roughdielectric">
            <string name="int_ior" value="bk7"/>
            <float name="alpha" value="0.06"/>
        </bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" value="1.35, 0.45, 0.5"/>
        <float name="radius" value="0.45"/>
        <bsdf type="dielectric"/>
    </shape>
    <shape type="cylinder">
        <point name="p0" value="0.6, 0, -1.0"/>
        <point name="p1" value="0.6, 1.6, -1.0"/>
        <float name="radius" value="0.35"/>
        <bsdf type="roughconductor">
            <string name="material" value="Cu"/>
            <float name="alpha" value="0.3"/>
        </bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world">
            <scale value="0.4"/>
            <rotate y="1" angle="25"/>
            <translate x="-0.5" y="0.4" z="-1.1"/>
        </transform>
        <bsdf type="blendbsdf">
            <float name="weight" value="0.35"/>
            <bsdf type="diffuse">
                <rgb name="reflectance" value="0.7, 0.15, 0.1"/>
            </bsdf>
            <bsdf type="roughconductor">
                <float name="alpha" value="0.1"/>
            </bsdf>
        </bsdf>
    </shape>
</scene>
"""


def build_mitsuba(out):
    write_text(out / "mitsuba" / "showcase.xml", MITSUBA_SHOWCASE)


def build(out, large_meshes=True):
    out = Path(out)
    WRITTEN.clear()
    build_shared(out)
    build_cornell(out)
    build_mis(out)
    build_delta(out)
    build_glass(out)
    build_furnace(out)
    build_large(out, large_meshes)
    build_sun(out)
    build_mitsuba(out)
    return sorted(p.relative_to(out).as_posix() for p in WRITTEN)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=str(HERE), help="output folder (default: scenes/)")
    ap.add_argument("--check", action="store_true", help="run numerical sanity checks afterwards")
    ap.add_argument("--large-meshes", action="store_true",
                    help="only generate the large PLY meshes (if missing) under --out")
    a = ap.parse_args(argv)
    t0 = time.time()
    if a.large_meshes:
        for p in ensure_large_meshes(a.out):
            print("%s (%.1f MB)" % (p, p.stat().st_size / 1e6))
        return
    files = build(a.out)
    total = sum(os.path.getsize(Path(a.out) / f) for f in files)
    print("wrote %d files (%.1f MB) to %s in %.1f s" % (len(files), total / 1e6, a.out, time.time() - t0))
    if a.check:
        sanity_checks(a.out)
        print("sanity checks passed")


if __name__ == "__main__":
    main()
