"""An independent numpy model of Nori's perspective camera (shared by the camera and render tests), written
from the matrices exactly as NORI_FORMAT.md states them for each dialect."""
import numpy as np


def nori_reference(width, height, fov, near, far, to_world, pos, dialect="upstream"):
    """sampleToCamera = inverse(S · T · P) with
    upstream: S = diag(-0.5, -0.5·aspect, 1), T = translate(-1, -1/aspect, 0);
    eth:      S = diag(+0.5, -0.5·aspect, 1), T = translate(+1, -1/aspect, 0).
    Returns ray origins, unit directions, tmin and tmax in units of the unit direction."""
    sx = {"upstream": -1.0, "eth": 1.0}[dialect]
    aspect = width / height
    recip = 1.0 / (far - near)
    cot = 1.0 / np.tan(np.radians(fov / 2.0))
    P = np.array([[cot, 0, 0, 0], [0, cot, 0, 0], [0, 0, far * recip, -near * far * recip], [0, 0, 1, 0]])
    S = np.diag([sx * 0.5, -0.5 * aspect, 1.0, 1.0])
    T = np.eye(4)
    T[:3, 3] = [sx * 1.0, -1.0 / aspect, 0.0]
    sample_to_camera = np.linalg.inv(S @ T @ P)
    pts = np.c_[pos[:, 0] / width, pos[:, 1] / height, np.zeros(len(pos)), np.ones(len(pos))]
    near_p = (sample_to_camera @ pts.T).T
    near_p = near_p[:, :3] / near_p[:, 3:4]
    d = near_p / np.linalg.norm(near_p, axis=1, keepdims=True)
    inv_z = 1.0 / d[:, 2]
    dw = (to_world[:3, :3] @ d.T).T  # Nori: ray.d = toWorld · d (not renormalised), mint = near / d.z
    lw = np.linalg.norm(dw, axis=1)
    o = to_world[:3, 3]
    return (np.broadcast_to(o, dw.shape), dw / lw[:, None], near * inv_z * lw, far * inv_z * lw)
