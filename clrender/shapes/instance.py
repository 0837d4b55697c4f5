"""Mitsuba 3's instancing: a ``shapegroup`` declares shapes without rendering them, and each ``instance`` renders
them again under its own ``to_world``.

```xml
<shape type="shapegroup" id="tree">               <!-- not rendered itself -->
    <shape type="ply"> ... </shape>                <!-- any shapes but emitters, groups and instances -->
    <shape type="sphere"> ... </shape>
</shape>
<shape type="instance">
    <ref id="tree"/>                               <!-- exactly one shapegroup -->
    <transform name="to_world"> ... </transform>   <!-- default identity -->
</shape>
```
clrender flattens instances when the scene is read: every instance adds world-space copies of its group's shapes
(a mesh's vertices mapped by the instance's to_world, normals by its inverse transpose; an analytic sphere's
centre, radius and frame; an SDF grid's to_world), sharing their BSDFs. Memory grows with the copies: a scene of many instances of a large
group costs what the same scene written out would. As in Mitsuba, the instance maps a surface's normal as a
covector, so a mirroring to_world keeps each surface's sides (a flattened mesh's winding is reversed to keep it);
a group may not hold emitters, groups or instances (Mitsuba refuses them too), and a sphere's copy needs a
to_world that scales uniformly (as a sphere's own).
"""
from __future__ import annotations

import copy

import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .sdfgrid import SDFGrid
from .shape import TRIANGLE_COORD_MAX
from .sphere import Sphere
from .trianglemesh import TriangleMesh


@register("shape", "shapegroup", fmt="mitsuba")
class ShapeGroup:
    children = ("shape",)

    def __init__(self, props, children, spec):
        self.shapes = []
        for c in children:
            where = c.spec.location
            if isinstance(c, (ShapeGroup, Instance)):
                raise SceneError(f'a shapegroup cannot hold a <shape type="{c.spec.type}"> (Mitsuba does not permit '
                                 'nested instancing either)', where)
            if getattr(c, "emitter", None) is not None:
                raise SceneError("a shape in a shapegroup cannot carry an emitter (Mitsuba does not support "
                                 "instancing of emitters either)", where)
            self.shapes.append(c)
        self.bsdf = self.emitter = None


@register("shape", "instance", fmt="mitsuba")
class Instance:
    children = ("shape",)

    def __init__(self, props, children, spec):
        self.to_world = np.asarray(props.get_transform("to_world").matrix, np.float64)
        groups = [c for c in children if isinstance(c, ShapeGroup)]
        others = [c for c in children if not isinstance(c, ShapeGroup)]
        if others:
            raise SceneError(f'an instance takes one shapegroup (a <ref id="..."/> to it), not a '
                             f'<shape type="{others[0].spec.type}">', others[0].spec.location)
        if len(groups) != 1:
            raise SceneError(f"an instance takes exactly one shapegroup, got {len(groups)}", spec.location)
        m = self.to_world
        self.location = props.location("to_world") if props.has("to_world") else spec.location
        if not np.all(np.isfinite(m)) or np.any(m[3] != [0, 0, 0, 1]) or abs(np.linalg.det(m[:3, :3])) < 1e-300:
            raise SceneError("an instance's to_world must be a finite, invertible affine transform", self.location)
        self.group = groups[0]
        self.bsdf = self.emitter = None

    def copies(self) -> list:
        """World-space copies of the group's shapes under this instance's to_world."""
        return [_transformed(s, self.to_world, self.location) for s in self.group.shapes]


def _transformed(shape, m: np.ndarray, where):
    out = copy.copy(shape)
    if isinstance(shape, TriangleMesh):
        with np.errstate(over="ignore", invalid="ignore"):
            mesh = shape.mesh.transformed(m)
        if np.linalg.det(m[:3, :3]) < 0:
            mesh.faces = np.ascontiguousarray(mesh.faces[:, [0, 2, 1]])
        used = mesh.positions[mesh.faces]
        if not (np.isfinite(used).all() and np.abs(used).max(initial=0.0) <= TRIANGLE_COORD_MAX):
            raise SceneError(f"an instance puts a vertex of '{shape.filename or shape.spec.type}' beyond "
                             f"{TRIANGLE_COORD_MAX:g} in world space: the single-precision triangle test may "
                             "overflow and miss it", where)
        out.mesh = mesh
        return out
    if isinstance(shape, Sphere):
        lin = m[:3, :3]
        scales = np.linalg.norm(lin, axis=0)
        gram = lin.T @ lin
        if (np.abs(gram - np.diag(np.diag(gram))).max() > 1e-5 * scales.max() ** 2
                or scales.max() - scales.min() > 1e-5 * scales.max()):
            raise SceneError("an instance of a sphere may only rotate, mirror, translate and scale it uniformly",
                             where)
        s = float(scales.mean())
        out.center = lin @ shape.center + m[:3, 3]
        out.radius = shape.radius * s
        out.frame = (lin / s) @ shape.frame
        out._check_extent(shape.spec)
        return out
    if isinstance(shape, SDFGrid):
        out.to_world = m @ shape.to_world
        SDFGrid.check_to_world(out.to_world, where)
        return out
    raise SceneError(f'clrender cannot instance a <shape type="{shape.spec.type}">', where)


def flatten(shapes: list) -> list:
    """The scene's shapes with shapegroups left out, each instance replaced by its copies, and meshes without a
    triangle of non-zero area (``empty``: never hit, as Mitsuba renders them) left out."""
    out = []
    for s in shapes:
        if isinstance(s, ShapeGroup):
            continue
        out.extend(c for c in (s.copies() if isinstance(s, Instance) else [s]) if not getattr(c, "empty", False))
    return out
