"""Mitsuba 3's ``sdfgrid``: the zero set of a signed distance function sampled on a grid, intersected exactly.

```xml
<shape type="sdfgrid">
    <string name="filename" value="torus.vol"/>      <!-- required: a one-channel Mitsuba .vol grid -->
    <string name="normals" value="smooth"/>          <!-- smooth (default) or analytic shading normals -->
    <transform name="to_world"> ... </transform>     <!-- the grid's unit cube [0, 1]^3 into the world;
                                                          default identity -->
    <bsdf type="..."/>
</shape>
```
The grid's values sit at the corners of its voxels: value (x, y, z) of an xres x yres x zres grid at
(x / (xres - 1), y / (yres - 1), z / (zres - 1)) of the unit cube (the file's own bounding box is ignored, as
Mitsuba ignores it). Between them the function is the trilinear interpolation of each voxel's eight corners, and
the surface is where it is 0; the outside is where it is positive (the normal points there). As in Mitsuba 3.9.1
(checked against its renders: tests/test_sdfgrid.py), the BVH holds each voxel whose corners do not all share
one sign, and a ray meets the first zero of the cubic the interpolation is along it (kernels/bvh_common.h
bvh_isect_voxel); the geometric normal is the gradient of that voxel's interpolation, the shading normal with
``smooth`` the blend of the eight neighbouring voxels' normalised gradients of Hansson-Söderlund et al. (JCGT
11(3), 2022), with ``analytic`` the geometric one (kernels/shapes/sdfgrid.h). Like Mitsuba's, the shape has no
uv (a texture is looked up at (0, 0)) and no area: it cannot carry an area emitter. Unlike Mitsuba's, a
to_world that rotates it is intersected exactly (Mitsuba warns and boxes the voxels as if it did not rotate),
and so is an instance of it.
"""
from __future__ import annotations

import numpy as np

from ..accel.primitives import SdfVoxels
from ..device import dispatch
from ..errors import SceneError
from ..scene.registry import register
from ..textures.bitmap import choice
from ..volumes.gridvolume import read_vol
from .shape import TRIANGLE_COORD_MAX, Shape

NORMALS = ("analytic", "smooth")
#: how far each voxel's unit cube is widened (kernels/bvh_common.h SDF_VOXEL_PAD); its box in the BVH covers it
VOXEL_PAD = 1e-5


def occupied_voxels(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The voxels of a (zres, yres, xres) grid whose corners do not all have one sign (the only ones the surface
    can pass through): their (x, y, z) indices (V, 3) and corner values (V, 8), corner x + 2 y + 4 z."""
    v = np.asarray(values, np.float32)
    corners = np.stack([v[dz:v.shape[0] - 1 + dz, dy:v.shape[1] - 1 + dy, dx:v.shape[2] - 1 + dx]
                        for dz in (0, 1) for dy in (0, 1) for dx in (0, 1)], axis=-1)
    # stacked z-major over (dz, dy, dx): index dx + 2 dy + 4 dz, the corner order the kernel reads
    occupied = ~(np.all(corners > 0, axis=-1) | np.all(corners < 0, axis=-1))
    z, y, x = np.nonzero(occupied)
    return np.stack([x, y, z], axis=1), corners[occupied]


@register("shape", "sdfgrid", fmt="mitsuba")
class SDFGrid(Shape):
    kernel = "shapes/sdfgrid.h"
    PARAMS = [("to_object", "float4", 3), ("res", "uint4"), ("extent", "float")]

    def __init__(self, props, children, spec):
        if not props.has("filename"):
            raise SceneError('<shape type="sdfgrid"> needs a <string name="filename"> (a one-channel Mitsuba .vol '
                             'grid; the "grid" tensor exists only in Mitsuba\'s Python API)', spec.location)
        loc = props.location("filename")
        self.filename = props.get_string("filename")
        data, _bbox = read_vol(self.filename, loc)
        if data.shape[-1] != 1:
            raise SceneError(f"SDF grid '{self.filename}' has {data.shape[-1]} channels; expected 1", loc)
        self.values = data[..., 0]
        if min(self.values.shape) < 2:
            raise SceneError(f"SDF grid '{self.filename}' is {' x '.join(map(str, self.values.shape[::-1]))}; it "
                             "needs at least 2 values along each axis (one voxel)", loc)
        self.smooth = NORMALS[choice(props, "normals", NORMALS, "smooth")] == "smooth"
        m = np.asarray(props.get_transform("to_world").matrix, np.float64)
        self.to_world = m
        self.location = props.location("to_world") if props.has("to_world") else spec.location
        self.check_to_world(m, self.location)
        self._attach(children, spec)
        if self.emitter is not None:
            raise SceneError("an SDF grid cannot carry an area emitter (it has no surface area to sample, as in "
                             "Mitsuba)", self.emitter.spec.location)
        if not len(occupied_voxels(self.values)[0]):
            raise SceneError(f"SDF grid '{self.filename}' has no surface: no voxel has corners of both signs "
                             "(Mitsuba refuses it too)", loc)

    @staticmethod
    def check_to_world(m: np.ndarray, where) -> None:
        if not (np.all(np.isfinite(m)) and np.allclose(m[3], (0, 0, 0, 1))
                and abs(np.linalg.det(m[:3, :3])) > 1e-30):
            raise SceneError("an SDF grid's to_world must be a finite, invertible affine transform", where)
        corners = np.array([[x, y, z, 1.0] for x in (0, 1) for y in (0, 1) for z in (0, 1)]) @ m.T
        if np.abs(corners[:, :3]).max() > TRIANGLE_COORD_MAX:
            raise SceneError(f"an SDF grid reaches beyond {TRIANGLE_COORD_MAX:g} in world space", where)

    def resolution(self) -> np.ndarray:
        """(xres, yres, zres)."""
        return np.array(self.values.shape[::-1], np.int64)

    def voxels(self, index: int) -> SdfVoxels:
        """The voxels the BVH holds, with world boxes and maps into their unit cubes (see SdfVoxels)."""
        res = self.resolution()
        ijk, corners = occupied_voxels(self.values)
        scale = (res - 1).astype(np.float64)
        # each voxel's (widened) cube in the grid's unit cube, its 8 corners taken to the world: the box around them
        lo = (ijk - VOXEL_PAD) / scale
        hi = (ijk + 1 + VOXEL_PAD) / scale
        pts = np.stack([np.stack([hi[:, 0] if cx else lo[:, 0], hi[:, 1] if cy else lo[:, 1],
                                  hi[:, 2] if cz else lo[:, 2]], axis=1)
                        for cx in (0, 1) for cy in (0, 1) for cz in (0, 1)], axis=1)
        w = pts @ self.to_world[:3, :3].T + self.to_world[:3, 3]
        wlo = np.nextafter(w.min(axis=1).astype(np.float32), np.float32(-np.inf))
        whi = np.nextafter(w.max(axis=1).astype(np.float32), np.float32(np.inf))
        # world -> voxel's unit cube: grid coordinates (to_object scaled by res - 1) less the voxel's index
        to_grid = np.linalg.inv(self.to_world)[:3] * scale[:, None]
        to_voxel = np.repeat(to_grid[None], len(ijk), axis=0)
        to_voxel[:, :, 3] -= ijk
        return SdfVoxels(wlo, whi, corners.astype(np.float32), to_voxel.astype(np.float32),
                         np.full(len(ijk), index, np.uint32))

    def fill(self, ctx, index, row):
        row["first"] = ctx.add_table("grid_data", "float", self.values.ravel())
        row["count"] = 1
        row["flags"] = 0
        p = row[dispatch.member_of(type(self))]
        p["to_object"] = np.linalg.inv(self.to_world)[:3].astype(np.float32)
        p["res"] = (*self.resolution(), int(self.smooth))
        p["extent"] = float(np.linalg.norm(self.to_world[:3, :3], axis=0).max())
        ctx.add_sdf_voxels(self.voxels(index))

    def area_distribution(self):
        return None, 0.0

