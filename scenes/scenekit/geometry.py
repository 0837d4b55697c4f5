"""Meshes made in code (quads, boxes, geodesic spheres, the displaced 'blob') and rotations."""
import math

import numpy as np

SEED = 20240611


def normalize(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def quad(p0, p1, p2, p3, normal):
    """A planar quad (corners in order around the boundary) as 2 triangles, with vn = normal and
    a winding that agrees with it."""
    V = np.array([p0, p1, p2, p3], dtype=np.float64)
    n = normalize(normal)
    if np.dot(np.cross(V[1] - V[0], V[2] - V[0]), n) < 0:
        V = V[::-1].copy()
    N = np.tile(n, (4, 1))
    F = np.array([[0, 1, 2], [0, 2, 3]])
    return V, N, F


def rect_xz(x0, x1, z0, z1, y, up=True):
    """Horizontal rectangle at height y, normal +y (up=True) or -y."""
    return quad((x0, y, z0), (x1, y, z0), (x1, y, z1), (x0, y, z1), (0, 1 if up else -1, 0))


def rot_y(deg):
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def box(center, half, rot_y_deg=0.0, inward=False):
    """Axis-aligned box (optionally rotated about +y), 6 faces with flat per-face normals
    (24 vertices, 12 triangles); normals outward unless inward=True."""
    R = rot_y(rot_y_deg)
    hx, hy, hz = half
    Vs, Ns, Fs = [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = np.zeros(3)
            n[axis] = sign
            u = np.zeros(3)
            u[(axis + 1) % 3] = 1.0
            w = np.zeros(3)
            w[(axis + 2) % 3] = 1.0
            h = np.array(half)
            c = n * h[axis]
            du, dw = u * h[(axis + 1) % 3], w * h[(axis + 2) % 3]
            corners = [c - du - dw, c + du - dw, c + du + dw, c - du + dw]
            V, N, F = quad(*corners, -n if inward else n)
            Fs.append(F + 4 * len(Vs))
            Vs.append(V)
            Ns.append(N)
    V = np.concatenate(Vs) @ R.T + np.asarray(center, dtype=np.float64)
    N = np.concatenate(Ns) @ R.T
    return V, N, np.concatenate(Fs)


def icosahedron():
    t = (1.0 + math.sqrt(5.0)) / 2.0
    V = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]],
        dtype=np.float64,
    )
    F = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]],
        dtype=np.int64,
    )
    return V, F


def geodesic_sphere(n):
    """Unit sphere: each icosahedron face split into n*n triangles (20 n^2 triangles,
    10 n^2 + 2 vertices), projected onto the sphere; outward winding.  Returns (V, F)."""
    IV, IF = icosahedron()
    # local grid of one face: point (i, j), 0 <= j <= i <= n, barycentric weights (n-i, i-j, j)
    ii, jj = [], []
    for i in range(n + 1):
        for j in range(i + 1):
            ii.append(i)
            jj.append(j)
    ii = np.array(ii)
    jj = np.array(jj)
    M = len(ii)
    lid = {}
    for k in range(M):
        lid[(ii[k], jj[k])] = k
    tris = []
    for i in range(n):
        for j in range(i + 1):
            tris.append((lid[(i, j)], lid[(i + 1, j)], lid[(i + 1, j + 1)]))
            if j < i:
                tris.append((lid[(i, j)], lid[(i + 1, j + 1)], lid[(i, j + 1)]))
    tris = np.array(tris, dtype=np.int64)
    assert len(tris) == n * n

    W = np.stack([n - ii, ii - jj, jj], axis=1)  # (M, 3)
    corners = np.broadcast_to(IF[:, None, :], (20, M, 3)).copy()  # (20, M, 3)
    weights = np.broadcast_to(W[None], (20, M, 3)).copy()
    corners[weights == 0] = 15
    order = np.argsort(corners, axis=2, kind="stable")
    c = np.take_along_axis(corners, order, 2).reshape(-1, 3)
    w = np.take_along_axis(weights, order, 2).reshape(-1, 3)
    key = (((((c[:, 0] * 4096 + w[:, 0]) * 16 + c[:, 1]) * 4096 + w[:, 1]) * 16 + c[:, 2]) * 4096
           + w[:, 2])
    uniq, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    cc = c[first]
    ww = w[first].astype(np.float64)
    IVp = np.zeros((16, 3))  # corner index 15 = 'no corner' (weight 0)
    IVp[:12] = IV
    P = (IVp[cc[:, 0]] * ww[:, 0:1] + IVp[cc[:, 1]] * ww[:, 1:2] + IVp[cc[:, 2]] * ww[:, 2:3]) / n
    P /= np.linalg.norm(P, axis=1, keepdims=True)
    F = inverse.reshape(20, M)[:, tris].reshape(-1, 3)
    # consistent outward winding
    fn = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
    flip = np.einsum("ij,ij->i", fn, P[F[:, 0]] + P[F[:, 1]] + P[F[:, 2]]) < 0
    F[flip] = F[flip][:, ::-1]
    assert len(P) == 10 * n * n + 2 and len(F) == 20 * n * n
    return P, F


def vertex_normals(V, F):
    """Area-weighted vertex normals (deterministic: bincount sums in index order)."""
    fn = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N = np.zeros_like(V)
    for k in range(3):
        for a in range(3):
            N[:, a] += np.bincount(F[:, k], weights=fn[:, a], minlength=len(V))
    return N / np.linalg.norm(N, axis=1, keepdims=True)


def blob_displacement(P, rng_seed=SEED):
    """Radius of the 'blob' along unit directions P: 1 + a sum of seeded sinusoids."""
    rng = np.random.default_rng(rng_seed)
    r = np.ones(len(P))
    for amp, freq in ((0.06, 2.5), (0.035, 5.0), (0.02, 9.0), (0.012, 17.0), (0.007, 31.0),
                      (0.004, 53.0)):
        for _ in range(2):
            d = normalize(rng.normal(size=3))
            phase = rng.uniform(0, 2 * math.pi)
            r += amp * np.sin(freq * (P @ d) + phase)
    return r


def blob(n):
    P, F = geodesic_sphere(n)
    V = P * blob_displacement(P)[:, None]
    return V, vertex_normals(V, F), F


def rotation_to(d):
    """(axis, angle_deg) of the right-handed rotation taking +z to unit vector d."""
    z = np.array([0.0, 0.0, 1.0])
    d = normalize(d)
    axis = np.cross(z, d)
    s = np.linalg.norm(axis)
    angle = math.degrees(math.atan2(s, d[2]))
    if s < 1e-12:
        axis = np.array([1.0, 0.0, 0.0])
    return normalize(axis), angle


def rodrigues(axis, angle_deg):
    a = normalize(axis)
    th = math.radians(angle_deg)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K


def round_vec(v, nd=4):
    return tuple(round(float(x), nd) + 0.0 for x in v)
