"""Write the generated meshes of the Mitsuba twin scenes (tests/mitsuba/scenes/meshes/):
``spheres.serialized`` holds two meshes written by clrender's own writer: 0, a tetrahedron with normals; 1, a
UV sphere of radius 1 without normals (Mitsuba and clrender then compute the same smooth normals).

    python tests/mitsuba/make_meshes.py
"""
from pathlib import Path

import numpy as np

from clrender.shapes.meshdata import MeshData
from clrender.shapes.serializedfile import write_serialized

OUT = Path(__file__).resolve().parent / "scenes" / "meshes"


def uv_sphere(rings: int = 8, segments: int = 12) -> MeshData:
    theta = np.linspace(0, np.pi, rings + 1)[1:-1]
    phi = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.cos(t), np.sin(t) * np.sin(p)], axis=-1).reshape(-1, 3)
    positions = np.concatenate([[[0, 1, 0]], ring, [[0, -1, 0]]])
    south = len(positions) - 1
    faces = []
    for j in range(segments):   # wound counter-clockwise seen from outside
        k = (j + 1) % segments
        faces.append([0, 1 + k, 1 + j])
        faces.append([south, 1 + (rings - 2) * segments + j, 1 + (rings - 2) * segments + k])
        for i in range(rings - 2):
            a, b = 1 + i * segments + j, 1 + i * segments + k
            c, d = a + segments, b + segments
            faces += [[a, b, d], [a, d, c]]
    return MeshData(positions=positions, normals=None, uvs=None, faces=np.array(faces))


def tetrahedron() -> MeshData:
    p = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], np.float64) / np.sqrt(3)
    faces = np.array([[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])
    positions = p[faces].reshape(-1, 3)              # flat: one vertex per corner
    normals = np.repeat(-p[[3, 2, 1, 0]], 3, axis=0)  # each face's normal points away from the opposite vertex
    return MeshData(positions=positions, normals=normals, uvs=None, faces=np.arange(12).reshape(4, 3))


if __name__ == "__main__":
    write_serialized(OUT / "spheres.serialized", [("tetrahedron", tetrahedron()), ("sphere", uv_sphere())])
    print(f"wrote {OUT / 'spheres.serialized'}")
