"""A large mesh made on the spot for tests that need loading and rendering to take a while: an n x n grid
of quads on a bumpy height field, as a binary little-endian PLY (2 n^2 triangles)."""
from pathlib import Path

import numpy as np


def write_grid_ply(path, n: int = 224) -> Path:
    u = np.linspace(-1.5, 1.5, n + 1)
    x, z = np.meshgrid(u, u)
    y = 0.15 * np.sin(5 * x) * np.cos(4 * z) + 0.5
    verts = np.stack([x, y, z], axis=-1).reshape(-1, 3).astype("<f4")
    i = np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]
    a, b, c, d = i, i + 1, i + n + 2, i + n + 1
    tris = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    faces = np.zeros(len(tris), dtype=[("n", "u1"), ("i", "<i4", (3,))])
    faces["n"], faces["i"] = 3, tris
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(verts)}\nproperty float x\n"
            f"property float y\nproperty float z\nelement face {len(faces)}\n"
            f"property list uchar int vertex_indices\nend_header\n")
    path = Path(path)
    path.write_bytes(head.encode() + verts.tobytes() + faces.tobytes())
    return path
