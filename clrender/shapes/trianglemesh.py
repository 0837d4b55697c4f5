"""Shared by the mesh plugins: load, bake into world space, drop degenerate triangles, pack the triangles.

Tables (kernels/shapes/mesh.h): positions/normals/uvs per vertex (normals and uvs zero where the mesh has none,
flagged by SHAPE_HAS_NORMALS / SHAPE_HAS_UVS), tri_index (i0, i1, i2, shape) per triangle; the row's first/count
are the mesh's range of tri_index. An emitting mesh is sampled by picking a triangle from its area CDF.
"""
from __future__ import annotations

import logging

import numpy as np

from ..device import dispatch
from ..errors import SceneError
from ..scene.transform import Transform
from .shape import Shape

log = logging.getLogger("clrender")


class TriangleMesh(Shape):
    kernel = "shapes/mesh.h"
    is_sphere = False

    def fill(self, ctx, index, row):
        m = self.mesh
        nv = len(m.positions)
        flags = 0
        p4 = np.zeros((nv, 4), np.float32)
        p4[:, :3] = m.positions
        base = ctx.add_table("positions", "float4", p4)
        n4 = np.zeros((nv, 4), np.float32)
        if m.normals is not None:
            flags |= dispatch.flag_defines()["SHAPE_HAS_NORMALS"]
            n4[:, :3] = m.normals
        ctx.add_table("normals", "float4", n4)     # one row per vertex either way: tri_index addresses both
        if m.uvs is not None:
            flags |= dispatch.flag_defines()["SHAPE_HAS_UVS"]
            ctx.add_table("uvs", "float2", m.uvs)
        else:
            ctx.add_table("uvs", "float2", np.zeros((nv, 2), np.float32))
        idx = np.empty((len(m.faces), 4), np.uint32)
        idx[:, :3] = m.faces + base
        idx[:, 3] = index
        row["first"] = ctx.add_table("tri_index", "uint4", idx)
        row["count"] = len(m.faces)
        row["flags"] = flags

    def area_distribution(self):
        areas = self.mesh.triangle_areas()
        area = float(areas.sum())
        cdf = np.cumsum(areas) / area if area > 0 else np.ones(len(areas))
        cdf[-1] = 1.0
        return cdf, area

    def _load(self, props, children, spec, loader):
        filename = props.get_string("filename")
        to_world: Transform = props.get_transform("toWorld")
        m = to_world.matrix
        if not np.all(np.isfinite(m)) or abs(np.linalg.det(m[:3, :3])) < 1e-300:
            raise SceneError("mesh toWorld is singular or not finite (e.g. a lookat whose up is parallel to "
                             "its viewing direction): points cannot be mapped to world space",
                             props.location("toWorld"))
        where = props.location("filename")
        try:
            mesh = loader(filename, where)
        except SceneError as e:
            if e.location == where:
                raise
            # The error names the mesh file (and line); add where the scene asked for that file.
            raise SceneError(f"in mesh {e}", where) from None
        mesh = mesh.transformed(to_world.matrix)
        mesh, dropped = mesh.drop_degenerate()
        if dropped:
            log.warning("%s: dropped %d degenerate triangle(s) of %s", spec.location, dropped, filename)
        if len(mesh.faces) == 0:
            raise SceneError(f"mesh '{filename}' has no non-degenerate triangles", spec.location)
        self.mesh = mesh
        self.filename = filename
        self.dropped = dropped
        self._attach(children, spec)
