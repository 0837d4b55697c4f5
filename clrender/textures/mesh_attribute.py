"""Mitsuba 3's `mesh_attribute` texture: an attribute of the mesh being shaded (a PLY file's vertex or face colours).

```xml
<shape type="ply">
    <string name="filename" value="colored.ply"/>
    <bsdf type="diffuse">
        <texture type="mesh_attribute" name="reflectance">
            <string name="name" value="vertex_color"/>   <!-- required: "vertex_<name>" or "face_<name>" -->
            <float name="scale" value="1"/>               <!-- default 1: multiplies the value -->
        </texture>
    </bsdf>
</shape>
```
As Mitsuba 3.9.1 (src/textures/mesh_attribute.cpp, src/shapes/ply.h): the PLY reader names a file's other properties
(`r g b` or `red green blue`: `vertex_color` / `face_color`; `<prefix>_0 _1 _2`, `_x _y _z`, ...: `vertex_<prefix>`,
one or three values; integer ones normalised and sRGB-decoded); a vertex attribute is interpolated barycentrically
over each triangle, a face attribute is constant over it; one value gives three equal channels.

The kernels look textures up by uv only, so each mesh whose BSDF holds one is given a texture of its own when the
mesh is loaded (``bake``): every triangle gets its own 2 x 2 block of texels, its corners the uvs of three of the
block's texel centres, and the fourth texel c11 = c10 + c01 - c00, so that the bitmap's bilinear lookup over the
block is exactly the barycentric interpolation (constant for a face attribute); the mesh's vertices are unshared
for this (64 bytes of texels a triangle, and three vertices of its own). Where a float is read (a blend weight), a one-value attribute is that value and a three-value one 0, as
Mitsuba's eval_1 gives (with a warning). Hence the limits: the BSDF must read no other texture through uv (an error
says so), and the texture cannot light an emitter.
"""
from __future__ import annotations

import copy
import logging
import math

import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .bitmap import Bitmap
from .texture import Texture

log = logging.getLogger("clrender")
WHERE = '<texture type="mesh_attribute">'


@register("texture", "mesh_attribute", fmt="mitsuba")
class MeshAttribute(Texture):
    """Stands for the attribute until a mesh bakes it (no kernel of its own: the baked one is a bitmap)."""

    def __init__(self, props, children, spec):
        self.name = props.get_string("name")
        if not (self.name.startswith("vertex_") or self.name.startswith("face_")):
            raise SceneError(f'{WHERE}: invalid attribute name "{self.name}": it must start with "vertex_" or '
                             f'"face_" (as in Mitsuba)', props.location("name"))
        self.scale = props.get_float("scale", 1.0)
        self.location = spec.location

    def max_value(self) -> float:
        return 0.0   # unknown until a mesh bakes it

    #: read where a float belongs (a blend weight, a roughness): Mitsuba's eval_1
    as_float = False

    def make_float_view(self) -> "MeshAttribute":
        view = copy.copy(self)
        view.as_float = True
        view.__dict__["_float_view"] = view
        return view

    def eval(self, uv):
        raise SceneError(f"{WHERE} has a value only on a mesh", self.location)

    def pack(self):
        raise SceneError(f"{WHERE} is read only by the BSDF of a mesh that has the attribute (here it is elsewhere, "
                         f"e.g. in an emitter or on a parametric shape)", self.location)


def baked_bitmap(image: np.ndarray, source: MeshAttribute) -> Bitmap:
    """A mesh's attribute as a bitmap (bilinear, clamped, identity to_uv) over the uvs ``bake`` gives the mesh: a
    Bitmap itself, so that the kernels' bitmap lookup (kernels/textures/bitmap.h) reads it."""
    out = Bitmap.__new__(Bitmap)
    out.image = np.ascontiguousarray(image, np.float32)
    out.raw = True
    out.filter, out.wrap = 0, 2
    out.to_uv = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    out.spec = getattr(source, "spec", None)
    return out


def _holders(obj, seen=None):
    """The MeshAttribute textures and the other textures reachable from a BSDF (through its attributes)."""
    seen = set() if seen is None else seen
    if id(obj) in seen:
        return [], []
    seen.add(id(obj))
    found, others = [], []
    values = list(vars(obj).values()) if hasattr(obj, "__dict__") else []
    for v in values:
        for item in (v if isinstance(v, (list, tuple)) else [v]):
            if isinstance(item, MeshAttribute):
                found.append(item)
            elif isinstance(item, Texture):
                others.append(item)
            elif hasattr(item, "__dict__") and type(item).__module__.startswith("clrender.bsdfs"):
                f, o = _holders(item, seen)
                found += f
                others += o
    return found, others


def _replaced(obj, old, new, memo):
    """``obj`` (a BSDF) with ``old`` replaced by ``new`` wherever it holds it, copying what changes."""
    if obj is old:
        return new
    if id(obj) in memo:
        return memo[id(obj)]
    if not (hasattr(obj, "__dict__") and type(obj).__module__.startswith("clrender.bsdfs")):
        return obj
    out = copy.copy(obj)
    memo[id(obj)] = out
    for k, v in list(vars(obj).items()):
        if isinstance(v, list):
            setattr(out, k, [_replaced(x, old, new, memo) for x in v])
        elif isinstance(v, tuple):
            setattr(out, k, tuple(_replaced(x, old, new, memo) for x in v))
        else:
            setattr(out, k, _replaced(v, old, new, memo))
    return out


def bake(mesh, bsdf, filename: str):
    """(mesh, bsdf) for a mesh whose BSDF reads a mesh attribute: unshared vertices with the blocks' uvs, and a copy
    of the BSDF reading the baked texture; unchanged where it reads none."""
    found, others = _holders(bsdf)
    if not found:
        return mesh, bsdf
    if others:
        raise SceneError(f"{WHERE}: the BSDF of mesh '{filename}' reads another texture beside it, which clrender "
                         f"cannot do (the attribute takes over the mesh's uvs)", found[0].location)
    f = mesh.faces
    n = len(f)
    side = max(1, math.ceil(math.sqrt(n)))
    k = np.arange(n)
    bx, by = 2 * (k % side), 2 * (k // side)
    size = 2 * side
    for attr in dict.fromkeys(found):   # each texture (a colour and its float view are two) on the same blocks
        values = mesh.attributes.get(attr.name)
        if values is None:
            have = ", ".join(sorted(mesh.attributes)) or "none"
            raise SceneError(f"{WHERE}: mesh '{filename}' has no attribute \"{attr.name}\" (it has: {have})",
                             attr.location)
        values = np.asarray(values, np.float64) * attr.scale
        if attr.as_float and values.shape[1] != 1:   # Mitsuba's eval_1 of a 3-value attribute is 0
            log.warning("%s: %s \"%s\" has %d values where a float is read: 0, as in Mitsuba 3.9.1",
                        attr.location, WHERE, attr.name, values.shape[1])
            values = np.zeros((len(values), 1))
        values = np.repeat(values, 3, axis=1) if values.shape[1] == 1 else values[:, :3]
        if attr.name.startswith("vertex_"):
            c00, c10, c01 = values[f[:, 0]], values[f[:, 1]], values[f[:, 2]]
        else:
            c00 = c10 = c01 = values
        image = np.zeros((size, size, 3))
        image[by, bx], image[by, bx + 1], image[by + 1, bx] = c00, c10, c01
        image[by + 1, bx + 1] = c10 + c01 - c00
        bsdf = _replaced(bsdf, attr, baked_bitmap(image, attr), {})
    corner = lambda x, y: np.stack([(x + 0.5) / size, (y + 0.5) / size], axis=1)   # noqa: E731
    uvs = np.stack([corner(bx, by), corner(bx + 1, by), corner(bx, by + 1)], axis=1).reshape(-1, 2)
    flat = f.reshape(-1)
    baked = type(mesh)(positions=mesh.positions[flat], normals=None if mesh.normals is None else mesh.normals[flat],
                     uvs=uvs, faces=np.arange(3 * n).reshape(n, 3), attributes={})
    return baked, bsdf
