"""Triangle mesh data as loaded from OBJ/PLY files, before it is uploaded to the device.

`MeshData` is a plain container of per-vertex arrays plus a triangle index list. Loaders produce it in
object space; the scene baking step calls `transformed()` with the shape's `toWorld` matrix and then
`drop_degenerate()` so that the BVH and the area-light sampler never see zero-area triangles.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class MeshData:
    """An indexed triangle mesh.

    positions: (V, 3) float32
    normals:   (V, 3) float32 or None (None: shade with the face normal)
    uvs:       (V, 2) float32 or None
    faces:     (F, 3) int32 indices into the per-vertex arrays
    attributes: Mitsuba's mesh attributes by name: "vertex_<name>" (V, k), "face_<name>" (F, k) float32, k 1 or 3
               (a PLY file's other properties; what the mesh_attribute texture reads)
    """

    positions: np.ndarray
    normals: np.ndarray | None
    uvs: np.ndarray | None
    faces: np.ndarray
    attributes: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        # A coordinate beyond float32's range becomes infinite here; the mesh shape reports it with its location.
        with np.errstate(over="ignore"):
            self.positions = np.ascontiguousarray(self.positions, dtype=np.float32).reshape(-1, 3)
            if self.normals is not None:
                self.normals = np.ascontiguousarray(self.normals, dtype=np.float32).reshape(-1, 3)
            if self.uvs is not None:
                self.uvs = np.ascontiguousarray(self.uvs, dtype=np.float32).reshape(-1, 2)
        self.faces = np.ascontiguousarray(self.faces, dtype=np.int32).reshape(-1, 3)

    @property
    def vertex_count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def face_count(self) -> int:
        return int(self.faces.shape[0])

    def transformed(self, matrix: np.ndarray) -> "MeshData":
        """A copy with points mapped by the 4x4 `matrix` and normals by its inverse transpose.

        Normals are renormalised but deliberately not flipped for mirroring matrices (negative
        determinant): the inverse transpose alone is the correct map for a covector, and the emitting
        side of an area light is defined by the shading normal, so flipping would change the scene.
        Faces (and so the winding) are left as they are.
        """
        m = np.asarray(matrix, dtype=np.float64)
        if m.shape != (4, 4):
            raise ValueError(f"expected a 4x4 matrix, got shape {m.shape}")
        p = self.positions.astype(np.float64)
        ph = p @ m[:3, :3].T + m[:3, 3]
        w = p @ m[3, :3] + m[3, 3]
        # Affine matrices (the usual case) have w == 1; skip the divide to keep them bit-exact.
        if not np.all(w == 1.0):
            ph = ph / w[:, None]
        normals = None
        if self.normals is not None:
            nm = np.linalg.inv(m[:3, :3]).T
            n = self.normals.astype(np.float64) @ nm.T
            normals = _normalize_rows(n)
        return MeshData(
            positions=ph.astype(np.float32),
            normals=None if normals is None else normals.astype(np.float32),
            uvs=None if self.uvs is None else self.uvs.copy(),
            faces=self.faces.copy(),
            attributes=dict(self.attributes),
        )

    def triangle_areas(self) -> np.ndarray:
        """(F,) float64 areas; NaN/inf propagate so callers can reject non-finite triangles."""
        return 0.5 * np.linalg.norm(self._edge_cross(), axis=1)

    def face_normals(self) -> np.ndarray:
        """(F, 3) float64 unit normals cross(v1 - v0, v2 - v0); zero rows for degenerate triangles."""
        return _normalize_rows(self._edge_cross())

    def drop_degenerate(self) -> tuple["MeshData", int]:
        """Remove triangles with repeated indices or a zero/non-finite area.

        Returns the cleaned mesh and the number of triangles dropped. Vertices are kept as they are
        (unreferenced vertices are harmless and keeping them keeps indices stable for debugging).
        """
        f = self.faces
        repeated = (f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 0] == f[:, 2])
        with np.errstate(invalid="ignore", over="ignore"):
            area = self.triangle_areas()
            bad = repeated | ~np.isfinite(area) | (area <= 0.0)
        dropped = int(np.count_nonzero(bad))
        if dropped == 0:
            return self, 0
        return (
            MeshData(
                positions=self.positions,
                normals=self.normals,
                uvs=self.uvs,
                faces=f[~bad],
                attributes={k: v[~bad] if k.startswith("face_") else v for k, v in self.attributes.items()},
            ),
            dropped,
        )

    def _edge_cross(self) -> np.ndarray:
        p = self.positions.astype(np.float64)
        f = self.faces
        v0 = p[f[:, 0]]
        with np.errstate(invalid="ignore", over="ignore"):
            return np.cross(p[f[:, 1]] - v0, p[f[:, 2]] - v0)


def _normalize_rows(v: np.ndarray) -> np.ndarray:
    """Rows scaled to unit length; zero (or non-finite) rows become zero instead of NaN."""
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        length = np.linalg.norm(v, axis=1, keepdims=True)
        out = np.where((length > 0) & np.isfinite(length), v / np.where(length > 0, length, 1.0), 0.0)
    return out
