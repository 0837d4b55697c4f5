"""The camera model (Nori's perspective camera) for the numerical sanity checks."""
import math

import numpy as np


def camera_to_world(cam):
    """The camera's toWorld as clrender computes a <lookat> (one camera model, not a copy)."""
    from clrender.scene.transform import Transform

    return np.array(Transform.lookat(cam["origin"], cam["target"], cam["up"]).matrix)


def project(cam, pts):
    """World points -> pixel coordinates (x right, y down) with upstream Nori's perspective camera
    (camera-space +x maps to the image's left: sx = (1 - x/(z tan))/2). Returns (px, py, z_cam)."""
    W, H = cam["width"], cam["height"]
    inv = np.linalg.inv(camera_to_world(cam))
    p = np.c_[np.asarray(pts, float), np.ones(len(pts))] @ inv.T
    t = math.tan(math.radians(cam["fov"]) / 2)
    aspect = W / H
    xn = p[:, 0] / (p[:, 2] * t)
    yn = p[:, 1] / (p[:, 2] * t)
    sx = 0.5 * (1.0 - xn)
    sy = 0.5 - 0.5 * aspect * yn
    return sx * W, sy * H, p[:, 2]
