"""What the shapes' test files share: a shape's sampling (the area emitter on it, shape_sample and shape_pdf through
the generated dispatch) chi-square-tested against its own pdf by tracing (tests/emitters/emitter_common.py's
machinery), and its render test: the shape, diffuse, in a constant environment, seen by a narrow camera."""
from pathlib import Path

import numpy as np

from clrender import load_scene, render
from clrender.pack import pack_scene
from clrender.testing.plugin_checks import check_render_value
from emitters.emitter_common import Dev, run_chi2

#: the chi-square cases of the shapes' files, Šidák-corrected together
N_SHAPE_CASES = 9
SENSOR = ('<sensor type="perspective"><float name="fov" value="{fov}"/><transform name="to_world"><lookat '
          'origin="{o}" target="{t}" up="0.1, 1, 0.3"/></transform><film type="hdrfilm">'
          '<integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film></sensor>')


def _v(p):
    return ", ".join(f"{x:.9g}" for x in p)


def check_shape_sampling(tmp: Path, ctx, queue, kernels, shape_xml: str, ref, mode: int, seed: int):
    """`shape_xml` (a Mitsuba <shape> without its closing tag's content: `{emitter}` where the area emitter goes)
    as an area light, sampled from `ref`: the directions against the pdf the kernel gives each direction (mode 0:
    summed over every hit, for meshes; 1: the first hit, for analytic shapes)."""
    xml = ('<scene version="3.0.0">' + SENSOR.format(fov=30, o="0, 0, 10", t="0, 0, 0") +
           shape_xml.format(emitter='<emitter type="area"><rgb name="radiance" value="1"/></emitter>') + "</scene>")
    (tmp / "shape.xml").write_text(xml)
    dev = Dev(ctx, queue, kernels, pack_scene(load_scene(tmp / "shape.xml")))
    r = run_chi2(dev, 0, np.asarray(ref, np.float64), mode, 200_000, 16, seed, n_tests=N_SHAPE_CASES)
    assert r.passed, r.message
    assert r.dof >= 3, f"too few cells for a meaningful test ({r.dof})"


def check_shape_furnace_render(tmp: Path, shape_xml: str, origin, target, albedo=0.6):
    """The shape (`{emitter}` left empty), diffuse of `albedo`, in a constant environment of radiance 1, seen from
    `origin` at the point `target` of its surface by a 0.05-degree camera: a convex shape seen from outside
    reflects only the environment, so the image is its albedo."""
    bsdf = f'<bsdf type="diffuse"><rgb name="reflectance" value="{albedo}"/></bsdf>'
    xml = ('<scene version="3.0.0"><integrator type="path"/>' +
           SENSOR.format(fov=0.05, o=_v(origin), t=_v(target)) + shape_xml.format(emitter=bsdf) +
           '<emitter type="constant"/></scene>')
    (tmp / "furnace.xml").write_text(xml)
    check_render_value(render(load_scene(tmp / "furnace.xml"), spp=1024, seed=1), albedo)


def surface_points(mesh, n=2000, seed=1):
    """Random points on the mesh: (position, interpolated uv, interpolated normal or None, face normal)."""
    rng = np.random.default_rng(seed)
    f = rng.integers(0, len(mesh.faces), n)
    b = rng.random((n, 2))
    flip = b.sum(1) > 1
    b[flip] = 1 - b[flip]
    w = np.c_[1 - b.sum(1), b]
    idx = mesh.faces[f]
    p = np.einsum("ij,ijk->ik", w, mesh.positions[idx].astype(np.float64))
    uv = np.einsum("ij,ijk->ik", w, mesh.uvs[idx].astype(np.float64))
    tri = mesh.positions[idx].astype(np.float64)
    ng = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    ng /= np.linalg.norm(ng, axis=1, keepdims=True)
    ns = None
    if mesh.normals is not None:
        ns = np.einsum("ij,ijk->ik", w, mesh.normals[idx].astype(np.float64))
        ns /= np.linalg.norm(ns, axis=1, keepdims=True)
    return p, uv, ns, ng


def closed_mesh():
    """The mesh the file shapes are tested with: an icosphere of 80 faces wound outward (radius 0.8 about
    (0.1, -0.2, 0.3)): (vertices, faces, a face's centroid, its outward normal)."""
    from icosphere import icosphere

    v, f = icosphere(1)
    v = 0.8 * v + [0.1, -0.2, 0.3]
    tri = v[f[5]]
    n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
    return v, np.asarray(f), tri.mean(axis=0), n / np.linalg.norm(n)


def check_file_shape(tmp: Path, ctx, queue, kernels, kind: str, filename: str, seed: int):
    """A file shape (`kind` reading `filename`, written from `closed_mesh`) sampled as an area light from outside
    (mode 0: every hit) and rendered in the furnace, seen along a face's normal."""
    _, _, c, n = closed_mesh()
    shape = f'<shape type="{kind}"><string name="filename" value="{tmp / filename}"/>{{emitter}}</shape>'
    check_shape_sampling(tmp, ctx, queue, kernels, shape, (1.5, 0.6, -0.4), 0, seed=seed)
    check_shape_furnace_render(tmp, shape, c + 3 * n, c)
