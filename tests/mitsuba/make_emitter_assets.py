"""Generate the small image and mesh assets of the emitter/texture twin scenes (tests/mitsuba/scenes/):

    python tests/mitsuba/make_emitter_assets.py

- textures/sky.exr: a 32 x 16 latitude-longitude sky (blue gradient above the horizon, a warm sun patch, a dark
  ground below), for the `envmap` emitter;
- textures/tiles.png: a 16 x 16 8-bit sRGB image of coloured tiles with a diagonal stripe, for `bitmap`;
- meshes/plane_uv.obj: a unit square in the xz plane (normal +y) with uvs (0,0) at (-1, 0, 1) ... (1,1) at
  (1, 0, -1), for textured floors and an emitting quad;
- meshes/ico.obj: an icosphere (2 subdivisions, unit radius, vertex normals), standing in for a sphere.

Everything is made here from formulas (deterministic); the files are committed and kept small.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from icosphere import icosphere  # noqa: E402  (tests/icosphere.py)

HERE = Path(__file__).resolve().parent / "scenes"


def sky(w=32, h=16) -> np.ndarray:
    v = (np.arange(h) + 0.5) / h                      # row 0 = zenith
    u = (np.arange(w) + 0.5) / w
    theta = v * np.pi
    img = np.zeros((h, w, 3), np.float32)
    up = np.cos(theta)[:, None]
    img[:] = np.where(up[..., None] > 0, np.stack([0.25 + 0.3 * (1 - up), 0.4 + 0.3 * (1 - up), 0.9 + 0 * up], -1),
                      np.array([0.08, 0.06, 0.05]))
    img[3:5, 9:12] = [30.0, 22.0, 12.0]               # the sun: 3 x 2 pixels
    img[:, (u > 0.7) & (u < 0.75)] *= 0.3             # a darker meridian band: orientation shows
    return img.astype(np.float32)


def tiles(n=16) -> np.ndarray:
    y, x = np.mgrid[0:n, 0:n]
    colours = np.array([[230, 60, 40], [40, 170, 70], [50, 90, 220], [240, 210, 60]], np.uint8)
    img = colours[((x // 4) + 2 * (y // 8)) % 4]
    img[x == y] = [250, 250, 250]                     # a diagonal stripe: flips and mirrors show
    img[0, :] = [20, 20, 20]                          # a dark first row: which way v runs shows
    return img.astype(np.uint8)


def main() -> None:
    import OpenEXR
    from PIL import Image

    (HERE / "textures").mkdir(parents=True, exist_ok=True)
    (HERE / "meshes").mkdir(parents=True, exist_ok=True)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    OpenEXR.File(header, {"RGB": np.ascontiguousarray(sky())}).write(str(HERE / "textures" / "sky.exr"))
    Image.fromarray(tiles()).save(HERE / "textures" / "tiles.png")
    (HERE / "meshes" / "plane_uv.obj").write_text(
        "# unit square in the xz plane, normal +y, with uvs\n"
        "v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\n"
        "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n")
    v, f = icosphere(2)
    lines = ["# icosphere, 2 subdivisions, unit radius"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in v]
    lines += [f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in v]
    lines += [f"f {a + 1}//{a + 1} {b + 1}//{b + 1} {c + 1}//{c + 1}" for a, b, c in f]
    (HERE / "meshes" / "ico.obj").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
