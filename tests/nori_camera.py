"""An independent numpy model of Nori's perspective camera (shared by the camera and render tests)."""
import numpy as np


def nori_reference(width, height, fov, near, far, to_world, pos):
    """Nori: sampleToCamera = inverse(diag(0.5, -0.5 aspect, 1) * translate(1, -1/aspect, 0) * P)."""
    aspect = width / height
    recip = 1.0 / (far - near)
    cot = 1.0 / np.tan(np.radians(fov / 2.0))
    P = np.array([[cot, 0, 0, 0], [0, cot, 0, 0], [0, 0, far * recip, -near * far * recip], [0, 0, 1, 0]])
    S = np.diag([0.5, -0.5 * aspect, 1.0, 1.0])
    T = np.eye(4)
    T[:3, 3] = [1.0, -1.0 / aspect, 0.0]
    sample_to_camera = np.linalg.inv(S @ T @ P)
    pts = np.c_[pos[:, 0] / width, pos[:, 1] / height, np.zeros(len(pos)), np.ones(len(pos))]
    near_p = (sample_to_camera @ pts.T).T
    near_p = near_p[:, :3] / near_p[:, 3:4]
    d = near_p / np.linalg.norm(near_p, axis=1, keepdims=True)
    inv_z = 1.0 / d[:, 2]
    dw = (to_world[:3, :3] @ d.T).T
    o = to_world[:3, 3]
    return np.broadcast_to(o, dw.shape), dw / np.linalg.norm(dw, axis=1, keepdims=True), near * inv_z, far * inv_z
