"""Affine (4x4 homogeneous) transforms as used by Nori's ``<transform>`` property.

A :class:`Transform` keeps its matrix and, lazily, its inverse. The static constructors build the
matrices of the XML ops (``translate``, ``scale``, ``rotate``, ``matrix``, ``lookat``); they raise
``ValueError`` for degenerate input so that the XML parser can re-raise it with a file location.
Composition follows Nori: ``a @ b`` applies ``b`` first, and each XML op is left-multiplied onto the
transform accumulated so far.
"""
from __future__ import annotations

import numpy as np

# Relative tolerance under which an axis / up vector counts as zero or parallel.
_EPS = 1e-9


def _as_vec3(v, what: str) -> np.ndarray:
    a = np.asarray(v, dtype=np.float64).reshape(-1)
    if a.shape != (3,):
        raise ValueError(f"{what} needs 3 numbers, got {a.size}")
    return a


class Transform:
    """A 4x4 homogeneous transform with a cached inverse."""

    __slots__ = ("_m", "_inv")

    def __init__(self, matrix=None, *, inverse=None):
        if matrix is None:
            m = np.eye(4)
        else:
            m = np.array(matrix, dtype=np.float64)
            if m.shape != (4, 4):
                raise ValueError(f"a transform matrix must be 4x4, got shape {m.shape}")
        m.setflags(write=False)
        self._m = m
        if inverse is not None:
            inverse = np.array(inverse, dtype=np.float64)
            inverse.setflags(write=False)
        self._inv = inverse

    # --- construction -------------------------------------------------------------------------
    @staticmethod
    def translate(v) -> "Transform":
        t = _as_vec3(v, "translate")
        m = np.eye(4)
        m[:3, 3] = t
        inv = np.eye(4)
        inv[:3, 3] = -t
        return Transform(m, inverse=inv)

    @staticmethod
    def scale(v) -> "Transform":
        s = np.asarray(v, dtype=np.float64).reshape(-1)
        if s.size == 1:
            s = np.repeat(s, 3)
        if s.shape != (3,):
            raise ValueError(f"scale needs 3 numbers (or 1), got {s.size}")
        if np.any(s == 0.0):
            raise ValueError("scale by zero makes the transform singular")
        return Transform(np.diag([*s, 1.0]), inverse=np.diag([*(1.0 / s), 1.0]))

    @staticmethod
    def rotate(axis, angle_degrees: float, normalize: bool = True) -> "Transform":
        """Right-handed rotation about ``axis`` by ``angle_degrees``.

        ``normalize=False`` uses the axis as written, as Eigen's ``AngleAxis`` does when it is given an
        unnormalised axis (the ETH/Dartmouth Nori forks): R = c·I + s·[k]x + (1 - c)·k·kᵀ, which is then
        not a rotation but is what those renderers compute."""
        k = _as_vec3(axis, "rotate axis")
        n = np.linalg.norm(k)
        if not np.isfinite(n) or n < _EPS:
            raise ValueError("rotate axis has zero length")
        theta = float(angle_degrees)
        if not np.isfinite(theta):
            raise ValueError(f"rotate angle must be a finite number, got {angle_degrees}")
        unit = abs(n - 1.0) < 1e-12
        if normalize:
            k = k / n
        theta = np.radians(theta)
        c, s = np.cos(theta), np.sin(theta)
        kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
        r = c * np.eye(3) + s * kx + (1.0 - c) * np.outer(k, k)
        m = np.eye(4)
        m[:3, :3] = r
        if normalize or unit:
            inv = np.eye(4)
            inv[:3, :3] = r.T  # rotations are orthonormal: the transpose is exact
            return Transform(m, inverse=inv)
        if abs(np.linalg.det(r)) < 1e-12:
            raise ValueError("rotate with this unnormalised axis gives a singular matrix")
        return Transform(m)

    @staticmethod
    def from_rows(values) -> "Transform":
        """From 16 numbers in row-major order (the XML ``matrix`` op)."""
        a = np.asarray(values, dtype=np.float64).reshape(-1)
        if a.size != 16:
            raise ValueError(f"matrix needs 16 numbers, got {a.size}")
        m = a.reshape(4, 4)
        # A singular matrix would poison normals (inverse transpose) much later, far from the cause.
        if not np.all(np.isfinite(m)) or np.linalg.cond(m) > 1e12:
            raise ValueError("matrix is singular (not invertible)")
        return Transform(m)

    @staticmethod
    def lookat(origin, target, up, warnings: list | None = None) -> "Transform":
        """Camera-to-world frame: columns [left, newUp, dir, origin] (Nori's convention).

        An ``up`` that is zero or parallel to the viewing direction gives left = newUp = 0, as Nori computes
        it (Eigen's ``normalized()`` leaves a zero vector unchanged): a camera with such a frame sends every
        ray along ``dir``, and a course test file relies on that. A message is appended to ``warnings``."""
        o = _as_vec3(origin, "lookat origin")
        t = _as_vec3(target, "lookat target")
        u = _as_vec3(up, "lookat up")
        d = t - o
        dn = np.linalg.norm(d)
        if dn < _EPS * max(1.0, np.linalg.norm(o)):
            raise ValueError("lookat target equals origin (no viewing direction)")
        d = d / dn
        un = np.linalg.norm(u)
        left = np.cross(u / un, d) if un >= _EPS else np.zeros(3)
        ln = np.linalg.norm(left)
        if ln < 1e-6:
            if warnings is not None:
                warnings.append("lookat 'up' is zero or parallel to the viewing direction: the frame has no "
                                "left/up axes (as in Nori), so a camera using it sends every ray along the "
                                "viewing direction")
            left = np.zeros(3)
            new_up = np.zeros(3)
        else:
            left = left / ln
            new_up = np.cross(d, left)
        m = np.eye(4)
        m[:3, 0] = left
        m[:3, 1] = new_up
        m[:3, 2] = d
        m[:3, 3] = o
        return Transform(m)

    # --- access ---------------------------------------------------------------------------------
    @property
    def matrix(self) -> np.ndarray:
        """The 4x4 float64 matrix (read-only view)."""
        return self._m

    @property
    def inverse(self) -> "Transform":
        if self._inv is None:
            inv = np.linalg.inv(self._m)
            inv.setflags(write=False)
            self._inv = inv
        return Transform(self._inv, inverse=self._m)

    def is_identity(self, tol: float = 0.0) -> bool:
        return bool(np.all(np.abs(self._m - np.eye(4)) <= tol))

    def allclose(self, other: "Transform", **kw) -> bool:
        return bool(np.allclose(self._m, other.matrix, **kw))

    def __matmul__(self, other):
        if not isinstance(other, Transform):
            return NotImplemented
        inv = None
        if self._inv is not None and other._inv is not None:
            inv = other._inv @ self._inv
        return Transform(self._m @ other._m, inverse=inv)

    def __eq__(self, other):
        if not isinstance(other, Transform):
            return NotImplemented
        return bool(np.array_equal(self._m, other._m))

    __hash__ = None  # mutable-looking numeric content; equality is by value

    def __repr__(self) -> str:
        rows = "; ".join(" ".join(f"{x:g}" for x in row) for row in self._m)
        return f"Transform([{rows}])"

    # --- application ------------------------------------------------------------------------------
    def apply_point(self, p) -> np.ndarray:
        """Transform point(s) of shape (3,) or (N, 3), with the projective divide by w."""
        p = np.asarray(p, dtype=np.float64)
        m = self._m
        out = p @ m[:3, :3].T + m[:3, 3]
        w = np.asarray(p @ m[3, :3] + m[3, 3])
        if np.all(w == 1.0):
            return out
        return out / w[..., None]

    def apply_vector(self, v) -> np.ndarray:
        """Transform direction(s) of shape (3,) or (N, 3) (no translation, not normalised)."""
        v = np.asarray(v, dtype=np.float64)
        return v @ self._m[:3, :3].T

    def apply_normal(self, n) -> np.ndarray:
        """Transform normal(s) by the inverse transpose and normalise them (zero stays zero)."""
        n = np.asarray(n, dtype=np.float64)
        inv = self.inverse.matrix
        # (M^-T n) as row vectors is n @ M^-1 (upper-left 3x3).
        out = n @ inv[:3, :3]
        length = np.linalg.norm(out, axis=-1, keepdims=True)
        return np.divide(out, length, out=np.zeros_like(out), where=length > 0)
