"""Mitsuba 3's `gridvolume`: values on a 3-D grid read from a Mitsuba `.vol` file, interpolated.

```xml
<medium type="heterogeneous">
    <volume type="gridvolume" name="sigma_t">
        <string name="filename" value="smoke.vol"/>         <!-- required -->
        <string name="filter_type" value="trilinear"/>      <!-- trilinear (default) or nearest -->
        <string name="wrap_mode" value="clamp"/>            <!-- clamp (default), repeat or mirror -->
        <boolean name="use_grid_bbox" value="false"/>       <!-- true: the grid spans the file's bounding box
                                                                 (then to_world), not the unit cube; default false -->
        <float name="max_value" value="..."/>               <!-- optional: the largest value (the medium's
                                                                 majorant) instead of the grid's own -->
        <boolean name="raw" value="false"/>                 <!-- accepted: RGB rendering converts nothing -->
        <boolean name="accel" value="true"/>                <!-- accepted: GPU texture hardware, not used -->
        <transform name="to_world"> ... </transform>        <!-- the grid's unit cube [0, 1]^3 into the world -->
    </volume>
</medium>
```
The file (Mitsuba 3.9.1's VolumeGrid, little endian): the bytes 'VOL', the version byte 3, an int32 encoding (1:
float32, the only one), int32 xres, yres, zres, channels (1 or 3 here; Mitsuba's 6-channel grids fill no medium
parameter), six float32 of a bounding box (xmin ymin zmin xmax ymax zmax), then xres*yres*zres*channels float32
with x fastest: value (x, y, z, c) at ((z yres + y) xres + x) channels + c. A missing, truncated or malformed file
is an error naming the file and the XML line.

Lookups are Mitsuba's (Dr.Jit's Texture3f): a point is taken to the unit cube by the inverse of to_world (after
use_grid_bbox's map of the file's box onto it), voxel centres sit at (i + 0.5) / res, trilinear interpolation
between the eight nearest voxels or the nearest one, indices outside the grid wrapped by wrap_mode. Kernel:
kernels/volumes/gridvolume.h; the voxels go to the scene's `grid_data` table.
"""
from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from ..errors import SceneError, git_lfs_hint
from ..scene.registry import register
from ..textures.bitmap import WRAPS, choice, wrap_index   # the same wrap modes, numbered alike
from .volume import Volume

FILTERS = ("trilinear", "nearest")
HEADER_BYTES = 48


def write_vol(path, data, bbox=(0, 0, 0, 1, 1, 1)) -> None:
    """Write `data` (zres, yres, xres[, channels]) as a Mitsuba .vol file (float32) with bounding box `bbox`."""
    data = np.asarray(data, np.float32)
    if data.ndim == 3:
        data = data[..., None]
    z, y, x, c = data.shape
    head = b"VOL" + bytes([3]) + struct.pack("<5i", 1, x, y, z, c) + struct.pack("<6f", *bbox)
    Path(path).write_bytes(head + data.astype("<f4").tobytes())


def read_vol(path, location=None) -> tuple[np.ndarray, np.ndarray]:
    """The voxels of a .vol file as float32 (zres, yres, xres, channels) and its bounding box (6,); errors name the
    file and `location` (the XML line of the filename)."""
    path = Path(path)
    if not path.is_file():
        what = "not found" if not path.exists() else "is not a regular file"
        raise SceneError(f"volume file '{path}' {what}", location)
    raw = path.read_bytes()

    def bad(why):
        return SceneError(f"volume file '{path}': {why}", location)

    if len(raw) < HEADER_BYTES:
        raise bad(f"{len(raw)} bytes, shorter than the {HEADER_BYTES}-byte header of a Mitsuba .vol file")
    if raw[:3] != b"VOL":
        raise bad(f"starts with {raw[:3]!r}; expected b'VOL' (a Mitsuba .vol grid){git_lfs_hint(raw)}")
    if raw[3] != 3:
        raise bad(f"version {raw[3]}; expected 3 (the only one Mitsuba 3 reads)")
    encoding, x, y, z, c = struct.unpack_from("<5i", raw, 4)
    if encoding != 1:
        raise bad(f"encoding {encoding}; expected 1 (float32, the only one Mitsuba 3 reads)")
    if min(x, y, z) < 1:
        raise bad(f"resolution {x} x {y} x {z}; expected at least 1 voxel along each axis")
    if c not in (1, 3):
        raise bad(f"{c} channels; expected 1 (a density) or 3 (a colour)")
    bbox = np.array(struct.unpack_from("<6f", raw, 24), np.float64)
    count = x * y * z * c
    if len(raw) < HEADER_BYTES + 4 * count:
        raise bad(f"truncated: {x} x {y} x {z} x {c} float32 values need {HEADER_BYTES + 4 * count} bytes, the file "
                  f"has {len(raw)}")
    data = np.frombuffer(raw, "<f4", count, HEADER_BYTES).astype(np.float32).reshape(z, y, x, c)
    if not np.all(np.isfinite(data)):
        raise bad("holds NaN or infinite values")
    return data, bbox


@register("volume", "gridvolume", fmt="mitsuba")
class GridVolume(Volume):
    kernel = "volumes/gridvolume.h"
    PARAMS = [("to_local", "float4", 3), ("res", "uint4"), ("offset", "uint"), ("filter", "uint"), ("wrap", "uint")]

    def __init__(self, props, children, spec):
        self._read_to_world(props, spec)
        loc = props.location("filename") if props.has("filename") else spec.location
        if not props.has("filename"):
            raise SceneError('<volume type="gridvolume"> needs a <string name="filename"> (a Mitsuba .vol file)',
                             spec.location)
        self.filename = props.get_string("filename")
        self.data, self.file_bbox = read_vol(self.filename, loc)
        self.channels = self.data.shape[-1]
        self.filter = choice(props, "filter_type", FILTERS, "trilinear")
        self.wrap = choice(props, "wrap_mode", WRAPS, "clamp")
        props.get_bool("raw", False)
        props.get_bool("accel", True)
        if props.get_bool("use_grid_bbox", False):
            lo, hi = self.file_bbox[:3], self.file_bbox[3:]
            ext = hi - lo
            if not np.all(ext > 0):
                raise SceneError(f"use_grid_bbox: the file's bounding box {self.file_bbox.tolist()} is empty along "
                                 "an axis", props.location("use_grid_bbox"))
            to_cube = np.eye(4)
            to_cube[:3, :3] = np.diag(ext)
            to_cube[:3, 3] = lo
            self.to_world = self.to_world @ to_cube   # the unit cube onto the file's box, then to_world
        self.max_override = props.get_float("max_value") if props.has("max_value") else None

    def resolution(self) -> tuple[int, int, int]:
        z, y, x, _ = self.data.shape
        return x, y, z

    def max_value(self) -> float:
        return float(self.data.max()) if self.max_override is None else float(self.max_override)

    def min_value(self) -> float:
        return float(self.data.min())

    def clamp(self, lo: float, hi: float | None = None) -> int:
        """Values below `lo` (above `hi`) set to it, as a grid's interpolation ringing asks (a density a hair below
        0); returns how many there were."""
        out = int(np.count_nonzero(self.data < lo)) + (0 if hi is None else int(np.count_nonzero(self.data > hi)))
        if out:
            self.data = np.clip(self.data, lo, hi).astype(self.data.dtype)
        return out

    def eval(self, points) -> np.ndarray:
        points = np.asarray(points, np.float64)
        flat = points.reshape(-1, 3)
        local = flat @ self.to_local[:3, :3].T + self.to_local[:3, 3]
        res = np.array(self.resolution())
        u = local * res
        vox = self.data.astype(np.float64)
        if self.filter == 1:
            i = [wrap_index(np.floor(u[:, k]), res[k], self.wrap) for k in range(3)]
            out = vox[i[2], i[1], i[0]]
        else:
            c = u - 0.5
            c0 = np.floor(c)
            f = c - c0
            out = np.zeros((len(flat), self.channels))
            for corner in range(8):
                b = [(corner >> k) & 1 for k in range(3)]
                idx = [wrap_index(c0[:, k] + b[k], res[k], self.wrap) for k in range(3)]
                w = np.prod([f[:, k] if b[k] else 1 - f[:, k] for k in range(3)], axis=0)
                out += w[:, None] * vox[idx[2], idx[1], idx[0]]
        out = np.broadcast_to(out, (len(flat), 3)) if self.channels == 1 else out
        return np.asarray(out).reshape(points.shape[:-1] + (3,))

    def fill(self, row, ctx) -> None:
        p = row["gridvolume"]
        p["to_local"] = self.to_local[:3].astype(np.float32)
        p["res"] = (*self.resolution(), self.channels)
        p["offset"] = ctx.add_table("grid_data", "float", self.data.ravel())
        p["filter"] = self.filter
        p["wrap"] = self.wrap
