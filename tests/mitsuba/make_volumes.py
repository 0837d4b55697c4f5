"""Write the volume grids of the Mitsuba twin scenes (tests/mitsuba/scenes/volumes/, not committed: made at test
time, and by make_refs.py before Mitsuba reads them) from deterministic numpy functions, with clrender's writer.

- ``smoke.vol``: 20 x 24 x 16 densities in [0, 1], a plume of three soft blobs broken up by a product of sines
  (smoke-like, with empty voxels at the edges);
- ``tint.vol``: 4 x 4 x 4 colours in [0.5, 0.95] (an albedo grid with 3 channels);
- ``knot_sdf.vol``: 24 x 20 x 24 signed distances (scaled by 7, as grids written by other tools are not in the unit
  cube's units) of a tilted torus merged smoothly with a ball, with a dent carved out: the `sdfgrid` twins' shape
  (as many values along x as along z: Mitsuba 3.9.1 misplaces the voxels of other grids, see
  clrender/shapes/sdfgrid.py).

    python tests/mitsuba/make_volumes.py
"""
from pathlib import Path

import numpy as np

from clrender.volumes.gridvolume import write_vol

OUT = Path(__file__).resolve().parent / "scenes" / "volumes"


def smoke(res=(20, 24, 16)) -> np.ndarray:
    """Densities (z, y, x) at the voxel centres of a res = (x, y, z) grid over the unit cube."""
    x, y, z = (np.arange(n) / n + 0.5 / n for n in res)
    zz, yy, xx = np.meshgrid(z, y, x, indexing="ij")
    d = np.zeros_like(xx)
    for (cx, cy, cz), r in (((0.5, 0.25, 0.5), 0.22), ((0.4, 0.55, 0.55), 0.2), ((0.6, 0.78, 0.45), 0.16)):
        d += np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2 + (zz - cz) ** 2) / (r * r))
    d *= 0.6 + 0.4 * np.sin(11 * xx + 3) * np.sin(13 * yy + 1) * np.sin(9 * zz + 2)
    d = np.clip(d - 0.08, 0, None)
    return (d / d.max()).astype(np.float32)


def tint(res=4) -> np.ndarray:
    i = np.arange(res) / (res - 1)
    zz, yy, xx = np.meshgrid(i, i, i, indexing="ij")
    return np.stack([0.95 - 0.3 * xx, 0.5 + 0.45 * yy, 0.7 + 0.2 * zz * xx], axis=-1).astype(np.float32)


def knot_sdf(res=(24, 20, 24)) -> np.ndarray:
    """Signed distances (z, y, x) at the grid points i / (res - 1) of the unit cube: negative inside."""
    x, y, z = (np.arange(n) / (n - 1) for n in res)
    zz, yy, xx = np.meshgrid(z, y, x, indexing="ij")
    px, py, pz = xx - 0.48, yy - 0.5, zz - 0.5
    c, s = np.cos(0.5), np.sin(0.5)                       # the torus tilted about x
    ty, tz = c * py - s * pz, s * py + c * pz
    torus = np.hypot(np.hypot(px, ty) - 0.27, tz) - 0.1
    ball = np.sqrt((xx - 0.72) ** 2 + (yy - 0.3) ** 2 + (zz - 0.62) ** 2) - 0.16
    k = 0.06                                              # a smooth minimum: the two merge with a fillet
    h = np.clip(0.5 + 0.5 * (ball - torus) / k, 0, 1)
    d = ball * (1 - h) + torus * h - k * h * (1 - h)
    dent = np.sqrt((xx - 0.3) ** 2 + (yy - 0.25) ** 2 + (zz - 0.75) ** 2) - 0.12
    return (7.0 * np.maximum(d, -dent)).astype(np.float32)


def write_volumes(out: Path = OUT) -> None:
    """(Re)write the grids; the same bytes every time."""
    out.mkdir(parents=True, exist_ok=True)
    write_vol(out / "smoke.vol", smoke())
    write_vol(out / "tint.vol", tint())
    write_vol(out / "knot_sdf.vol", knot_sdf())


if __name__ == "__main__":
    write_volumes()
