"""Shared by the mesh plugins: load, bake into world space, drop degenerate triangles."""
from __future__ import annotations

import logging

import numpy as np

from ..errors import SceneError
from ..scene.transform import Transform
from .shape import Shape

log = logging.getLogger("clrender")


class TriangleMesh(Shape):
    is_sphere = False

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
