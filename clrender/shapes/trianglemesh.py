"""Shared by the mesh plugins: load, bake into world space, drop degenerate triangles, pack the triangles.

Tables (kernels/shapes/mesh.h): normals/uvs per vertex (zero where the mesh has none, flagged by
SHAPE_HAS_NORMALS / SHAPE_HAS_UVS); the positions and triangles go to PackContext.add_mesh, from which pack_scene
makes the primitive table (the vertices) and tri_index (vertex indices), both in BVH leaf order, and the
mesh_vertices row that gives a triangle's shape. The row's count is the mesh's triangle count; an emitting mesh is
sampled by picking a triangle from its area CDF, and its first is the offset of its triangles' leaf references
in the tri_refs table.
"""
from __future__ import annotations

import logging

import numpy as np

from ..device import dispatch
from ..device.layout import NONE
from ..errors import SceneError
from ..scene.transform import Transform
from .meshdata import _normalize_rows
from .shape import TRIANGLE_COORD_MAX, Shape

log = logging.getLogger("clrender")


class TriangleMesh(Shape):
    kernel = "shapes/mesh.h"

    def fill(self, ctx, index, row):
        m = self.mesh
        nv = len(m.positions)
        flags = 0
        base = ctx.add_mesh(index, m.positions, m.faces)
        normals = np.zeros((nv, 3), np.float32)
        if m.normals is not None:
            flags |= dispatch.flag_defines()["SHAPE_HAS_NORMALS"]
            normals = m.normals
        # one row per vertex either way: a triangle's vertex indices address both
        if ctx.add_table("normals", "ushort", fixed_normals(normals)) != 3 * base:
            raise AssertionError("the normals table is out of step with the mesh vertices")
        if m.uvs is not None:
            flags |= dispatch.flag_defines()["SHAPE_HAS_UVS"]
            ctx.add_table("uvs", "float2", m.uvs)
        else:
            ctx.add_table("uvs", "float2", np.zeros((nv, 2), np.float32))
        row["first"] = NONE         # pack_scene: emitting meshes' offset in the tri_refs table
        row["count"] = len(m.faces)
        row["flags"] = flags

    def area_distribution(self):
        areas = self.mesh.triangle_areas()
        area = float(areas.sum())
        cdf = np.cumsum(areas) / area if area > 0 else np.ones(len(areas))
        cdf[-1] = 1.0
        return cdf, area

    def _load(self, props, children, spec, loader, to_world_name: str = "toWorld", prepare=None, generate=None,
              name: str | None = None):
        """Read (``loader``, or ``generate()`` for a built-in mesh called ``name``), transform and clean the mesh;
        ``prepare(mesh)`` (Mitsuba's options) runs on the world-space mesh before degenerate triangles are
        dropped."""
        filename = props.get_string("filename") if loader is not None else None
        to_world: Transform = props.get_transform(to_world_name)
        m = to_world.matrix
        if not np.all(np.isfinite(m)) or abs(np.linalg.det(m[:3, :3])) < 1e-300:
            raise SceneError("mesh toWorld is singular or not finite (e.g. a lookat whose up is parallel to "
                             "its viewing direction): points cannot be mapped to world space",
                             props.location(to_world_name))
        where = props.location("filename") if filename is not None else None
        try:
            mesh = loader(filename, where) if filename is not None else generate()
        except SceneError as e:
            if e.location == where:
                raise
            # The error names the mesh file (and line); add where the scene asked for that file.
            raise SceneError(f"in mesh {e}", where) from None
        with np.errstate(over="ignore", invalid="ignore"):
            mesh = mesh.transformed(to_world.matrix)
        used = mesh.positions[mesh.faces]
        if not (np.isfinite(used).all() and np.abs(used).max(initial=0.0) <= TRIANGLE_COORD_MAX):
            # beyond it a triangle would be missed (or, past float32's range, dropped as degenerate) without a word
            raise SceneError(f"mesh '{filename or name}': a vertex lies beyond {TRIANGLE_COORD_MAX:g} in world "
                             f"space (its coordinates mapped by {to_world_name}): the single-precision triangle "
                             f"test may overflow and miss it", where or spec.location)
        if prepare is not None:
            mesh = prepare(mesh)
        mesh, dropped = mesh.drop_degenerate()
        if dropped:
            log.warning("%s: dropped %d degenerate triangle(s) of %s", spec.location, dropped, filename or name)
        #: a Mitsuba mesh with no triangle of non-zero area, left out of the scene (Scene's flatten)
        self.empty = False
        if len(mesh.faces) == 0:
            emitting = any(c.spec.tag == "emitter" for c in children)
            if getattr(spec, "format", "nori") != "mitsuba" or emitting:
                # Mitsuba 3.9.1 refuses an emitting one too: its area distribution has no mass to sample
                raise SceneError(f"mesh '{filename or name}' has no non-degenerate triangles"
                                 + (" (an area light must have some area)" if emitting else ""), spec.location)
            # Mitsuba 3.9.1 loads it (warning only where it computes normals) and renders the scene around it,
            # since a triangle of zero area is never hit (Bitterli's staircase has one, Mesh432.obj)
            log.warning("%s: mesh '%s' has no triangle of non-zero area (%d degenerate): left out of the scene, "
                        "which renders as in Mitsuba", spec.location, filename or name, dropped)
            self.empty = True
        self.mesh = mesh
        self.filename = filename
        self.dropped = dropped
        self._attach(children, spec)
        if not self.empty:   # a mesh_attribute texture in the BSDF: the mesh's attribute, baked into a bitmap
            from ..textures.mesh_attribute import bake

            self.mesh, self.bsdf = bake(self.mesh, self.bsdf, filename or name)


def fixed_normals(normals) -> np.ndarray:
    """Vertex normals (V, 3) as 16-bit signed fixed point (x 32767, two's complement bits), the normals table's
    element (kernels/shapes/mesh.h decodes them): 6 bytes a vertex instead of 12, for issue 11's memory target.
    The normals are unit vectors (MeshData.transformed normalises every mesh's) or zero; a component is rounded
    to 1/65534, so a normal turns by at most sqrt(3) / 65534 = 2.7e-5 rad. Half floats, stored here before,
    turned one by up to 4e-4 rad: the same on every vertex of a flat surface, which biased its shading by up to
    1e-3 (a cosine's relative error is the turn times the tangent of its angle; issue 24: Mitsuba's instanced
    rectangles 7e-5 off). A row longer than 1 is scaled to unit length; non-finite ones become 0, which the
    kernel treats as no normal (the face's own)."""
    n = np.asarray(normals, np.float64).reshape(-1, 3)
    n = np.where(np.isfinite(n).all(axis=1, keepdims=True), n, 0.0)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.where(length > 1.0, n / np.maximum(length, 1.0), n)
    return np.rint(np.clip(n, -1.0, 1.0) * 32767.0).astype(np.int16).view(np.uint16)


def _corner_terms(p: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each face's unit normal (0 for a degenerate face) and (T, 3) its angle at each of its corners."""
    n = _normalize_rows(np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]]))
    angles = np.empty(f.shape)
    for j in range(3):
        a = p[f[:, (j + 1) % 3]] - p[f[:, j]]
        b = p[f[:, (j + 2) % 3]] - p[f[:, j]]
        a /= np.maximum(np.linalg.norm(a, axis=1, keepdims=True), 1e-300)
        b /= np.maximum(np.linalg.norm(b, axis=1, keepdims=True), 1e-300)
        angles[:, j] = np.arccos(np.clip((a * b).sum(axis=1), -1.0, 1.0))
    return n, angles


def angle_weighted_normals(mesh) -> np.ndarray:
    """Smooth vertex normals as Mitsuba computes them for a mesh file without normals: each face's unit normal,
    weighted by the face's angle at the vertex, summed and normalised."""
    p = mesh.positions.astype(np.float64)
    n, angles = _corner_terms(p, mesh.faces)
    out = np.zeros_like(p)
    for j in range(3):
        np.add.at(out, mesh.faces[:, j], n * angles[:, j, None])
    return _normalize_rows(out)


def crease_normals(mesh, max_angle: float):
    """Mitsuba 0.x's ``maxSmoothAngle`` (degrees): the mesh's own normals dropped, vertices at the same position
    (and uv) welded, and at each vertex the faces whose normals lie within ``max_angle`` of each other
    (transitively) share one new vertex, whose normal is theirs, angle-weighted as above. So a crease sharper
    than the angle stays sharp and smoother parts are smooth, whatever the file's vertex sharing was."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    from .meshdata import MeshData

    p = mesh.positions.astype(np.float64)
    f = mesh.faces
    key = p if mesh.uvs is None else np.hstack([p, mesh.uvs.astype(np.float64)])
    weld = np.unique(key, axis=0, return_inverse=True)[1].reshape(-1)
    n, angles = _corner_terms(p, f)
    corner_vertex = weld[f].reshape(-1)                       # corner c = 3 * face + j
    order = np.argsort(corner_vertex, kind="stable")
    ordered = corner_vertex[order]
    cos_max = np.cos(np.radians(max_angle))
    rows, cols = [], []
    k = 1
    while k < ordered.size:   # every pair of corners at one vertex: the i-th and the (i+k)-th of its run
        same = np.nonzero(ordered[k:] == ordered[:-k])[0]
        if same.size == 0:
            break
        a, b = order[same], order[same + k]
        close = (n[a // 3] * n[b // 3]).sum(axis=1) >= cos_max
        rows.append(a[close])
        cols.append(b[close])
        k += 1
    count = f.size
    rows = np.concatenate(rows) if rows else np.zeros(0, np.int64)
    cols = np.concatenate(cols) if cols else np.zeros(0, np.int64)
    graph = coo_matrix((np.ones(rows.size), (rows, cols)), shape=(count, count))
    labels = connected_components(graph, directed=False)[1]
    new_index = np.unique(labels, return_inverse=True)[1].reshape(-1)
    first = np.zeros(new_index.max() + 1, np.int64)
    first[new_index[::-1]] = np.arange(count)[::-1]          # a corner of each new vertex
    normals = np.zeros((first.size, 3))
    np.add.at(normals, new_index, np.repeat(n, 3, axis=0) * angles.reshape(-1, 1))
    old = f.reshape(-1)[first]
    attributes = {k: v[old] if k.startswith("vertex_") else v for k, v in mesh.attributes.items()}
    return MeshData(positions=mesh.positions[old], normals=_normalize_rows(normals),
                    uvs=None if mesh.uvs is None else mesh.uvs[old], faces=new_index.reshape(-1, 3),
                    attributes=attributes)


class MitsubaMeshOptions:
    """What Mitsuba's mesh shapes (obj, ply, serialized, cube) share: ``to_world``; ``face_normals`` (flat
    shading: drop the vertex normals); without it a file without normals gets Mitsuba's smooth angle-weighted
    ones; ``flip_normals`` turns the surface around (reversed winding and negated normals: the side an area light
    emits from and a one-sided BSDF reflects on)."""

    def _load_mitsuba(self, props, children, spec, loader, generate=None, name=None):
        face_normals = props.get_bool("face_normals", False) if loader is not None else False
        flip = props.get_bool("flip_normals", False)
        # Mitsuba 0.x's maxSmoothAngle (old files; Mitsuba 3 has none): normals rebuilt with that crease angle
        crease = props.get_float("max_smooth_angle", None) if loader is not None else None
        if crease is not None and not 0 <= crease <= 180:
            raise SceneError(f"max_smooth_angle must be between 0 and 180 degrees, got {crease}",
                             props.location("max_smooth_angle"))

        def prepare(mesh):
            from .meshdata import MeshData

            if crease is not None and not face_normals:
                mesh = crease_normals(mesh, crease)
            normals = None if face_normals else (
                mesh.normals if mesh.normals is not None else angle_weighted_normals(mesh))
            faces = mesh.faces
            if flip:
                faces = faces[:, [0, 2, 1]]
                normals = None if normals is None else -normals
            return MeshData(positions=mesh.positions, normals=normals, uvs=mesh.uvs, faces=faces,
                            attributes=mesh.attributes)

        self._load(props, children, spec, loader, "to_world", prepare, generate, name)

    def _load_generated(self, props, children, spec, generate, name: str):
        self._load_mitsuba(props, children, spec, None, generate, name)
