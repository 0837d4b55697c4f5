"""Directions that BSDF tests and their reference scripts evaluate at, in the local shading frame (z = normal)."""
from __future__ import annotations

import numpy as np


def wi_at(theta_deg: float, side: int = 1, phi_deg: float = 0.0) -> np.ndarray:
    """The unit direction at polar angle theta (degrees) and azimuth phi, on the side `side` (+1 above, -1 below)."""
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), side * np.cos(t)])


def refracted(wi: np.ndarray, eta: float) -> np.ndarray | None:
    """wi refracted through a smooth interface of relative index `eta` (inside over outside; wi.z > 0: arriving
    from outside); None at total internal reflection."""
    e = eta if wi[2] > 0 else 1 / eta
    s2 = (1 - wi[2] ** 2) / (e * e)
    if s2 >= 1:
        return None
    return np.array([-wi[0] / e, -wi[1] / e, -np.sign(wi[2]) * np.sqrt(1 - s2)])
