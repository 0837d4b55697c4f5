"""Meshes of Mitsuba 3's parametric shapes, in object space, with Mitsuba's uv parametrisation.

The BVH knows two primitive kinds (triangles and spheres), so the flat and ruled shapes are meshed: a rectangle is
exactly two triangles; a disk and a cylinder are meshed finely enough (``SEGMENTS`` around) that their surfaces lie
within 2e-5 of their radius of the true ones (1 - cos(pi / SEGMENTS)), far below what an image can show, with the
cylinder's vertex normals exact. Conventions (checked against Mitsuba 3.9's own intersections):

* rectangle: [-1, 1]^2 in the xy plane, normal +z, uv = ((x + 1) / 2, (y + 1) / 2);
* disk: the unit disk in the xy plane, normal +z, uv = (r, phi / 2pi) with phi = atan2(y, x) in [0, 2pi);
* cylinder: radius 1 about the z axis from z = 0 to z = 1, open ends, normals outward, uv = (phi / 2pi, z).
"""
from __future__ import annotations

import numpy as np

from .meshdata import MeshData

#: segments around the disk and the cylinder
SEGMENTS = 512


def rectangle() -> MeshData:
    p = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float64)
    uv = (p[:, :2] + 1) / 2
    return MeshData(p, None, uv, np.array([[0, 1, 2], [0, 2, 3]]))


def _angles(n: int) -> np.ndarray:
    return np.arange(n + 1) * (2 * np.pi / n)          # the seam's vertices twice: u wraps 1 -> 0 there


def disk(n: int = SEGMENTS) -> MeshData:
    """A fan of n triangles; each has its own centre vertex whose phi is the triangle's middle angle, so v
    interpolates within each sector instead of averaging across the disk."""
    phi = _angles(n)
    rim = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=1)
    mid = (phi[:-1] + phi[1:]) / 2
    centres = np.zeros((n, 3))
    p = np.concatenate([rim, centres])
    uv = np.concatenate([np.stack([np.ones_like(phi), phi / (2 * np.pi)], axis=1),
                         np.stack([np.zeros(n), mid / (2 * np.pi)], axis=1)])
    i = np.arange(n)
    faces = np.stack([n + 1 + i, i, i + 1], axis=1)     # counter-clockwise seen from +z: normal +z
    return MeshData(p, None, uv, faces)


def cylinder(n: int = SEGMENTS) -> MeshData:
    phi = _angles(n)
    ring = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    k = len(phi)
    p = np.concatenate([np.c_[ring, np.zeros(k)], np.c_[ring, np.ones(k)]])
    normals = np.concatenate([np.c_[ring, np.zeros(k)]] * 2)
    u = phi / (2 * np.pi)
    uv = np.concatenate([np.c_[u, np.zeros(k)], np.c_[u, np.ones(k)]])
    i = np.arange(n)
    faces = np.concatenate([np.stack([i, i + 1, k + i + 1], axis=1), np.stack([i, k + i + 1, k + i], axis=1)])
    return MeshData(p, normals, uv, faces)
