"""The references of checkerboard_ttest.xml, integrated in numpy from the file's own scenes.

Each case is a 1 × 1 image under the `direct` integrator: a point light over a diffuse surface whose albedo is a
checkerboard_color. As in Nori's ttest (clrender/testing/nori.py), a sample is a uniform position on the image
plane, (x, y, 1) with |x|, |y| <= tan(fov/2) in the camera frame of the lookat; its value is the luminance of
albedo/π · Φ/(4π) · cosθ/d² at the first hit (0 where the ray misses or the light is behind the surface), and the
reference is the mean over the square, by Monte Carlo with its standard error.

The plane is uvplane.obj under its <scale> (its uv an affine map of (x, z), read from the .obj); the analytic
sphere has uv = (atan2(n.y, n.x)/2π wrapped to [0, 1), acos(n.z)/π). value1 where
floor(u/su − du) + floor(v/sv − dv) is even (delta in cells). `variant` gives what a wrong convention would:
"uv_delta" (delta in uv units: floor((u − du)/su)), "no_wrap" (the sphere's u left in (−½, ½]), "half_turn"
(eth2023's u + ½).

    python tests/nori/checkerboard_refs.py [rays per case, default 4e7]   # the references and the variants
"""
from __future__ import annotations

import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
XML = HERE / "checkerboard_ttest.xml"
LUMINANCE = np.array([0.212671, 0.715160, 0.072169])   # Nori's Color3f::getLuminance


def _vec(text):
    return np.array([float(x) for x in text.replace(",", " ").split()])


def _props(node):
    """name -> value of a node's direct <float>/<point>/<vector>/<color>/<string> children."""
    return {c.get("name"): c.get("value") for c in node if c.get("name") is not None and c.get("value") is not None}


def _obj_uv_map(path):
    """(3, 2) matrix M with uv = (x, z, 1) @ M over the .obj's vertices (a flat y = 0 mesh, uv affine in x, z)."""
    v, vt, pairs = [], [], set()
    for line in path.read_text().splitlines():
        f = line.split()
        if f and f[0] == "v":
            v.append([float(x) for x in f[1:4]])
        elif f and f[0] == "vt":
            vt.append([float(x) for x in f[1:3]])
        elif f and f[0] == "f":
            pairs |= {tuple(int(i) - 1 for i in c.split("/")[:2]) for c in f[1:]}
    xz1 = np.array([[v[i][0], v[i][2], 1.0] for i, _ in sorted(pairs)])
    uv = np.array([vt[j] for _, j in sorted(pairs)])
    m = np.linalg.lstsq(xz1, uv, rcond=None)[0]
    assert np.allclose(xz1 @ m, uv) and np.allclose([v[i][1] for i, _ in pairs], 0), "uv is not affine in (x, z)"
    return np.round(m, 12)


def read_cases(path=XML):
    """The references and, per <scene>, the parameters the integration needs."""
    root = ET.parse(path).getroot()
    refs = [float(x) for x in root.find("string[@name='references']").get("value").split(",")]
    cases = []
    for scene in root.findall("scene"):
        cam = scene.find("camera")
        look = cam.find("transform/lookat")
        mesh = scene.find("mesh")
        tex = mesh.find("bsdf/texture")
        light = _props(scene.find("emitter"))
        t = _props(tex)
        case = dict(origin=_vec(look.get("origin")), target=_vec(look.get("target")), up=_vec(look.get("up")),
                    fov=float(_props(cam)["fov"]), light=_vec(light["position"]), power=_vec(light["power"]),
                    delta=_vec(t.get("delta", "0, 0")), scale=_vec(t.get("scale", "0.5, 0.5")),
                    value1=_vec(t.get("value1", "0")) * np.ones(3), value2=_vec(t.get("value2", "1")) * np.ones(3))
        if mesh.get("type") == "sphere":
            p = _props(mesh)
            case.update(shape="sphere", center=_vec(p["center"]), radius=float(p["radius"]))
        else:
            case.update(shape="plane", uv_map=_obj_uv_map(HERE / _props(mesh)["filename"]),
                        size=_vec(mesh.find("transform/scale").get("value")))
        cases.append(case)
    return refs, cases


def _hits(case, d):
    """Hit points, unit normals, uv and a hit mask of unit directions d (n, 3) from the camera."""
    o = case["origin"]
    if case["shape"] == "sphere":
        c, r = case["center"], case["radius"]
        oc = o - c
        b = d @ oc
        disc = b * b - (oc @ oc - r * r)
        t = -b - np.sqrt(np.maximum(disc, 0))
        x = o + t[:, None] * d
        n = (x - c) / r
        u = np.arctan2(n[:, 1], n[:, 0]) / (2 * np.pi)
        if case.get("variant") != "no_wrap":
            u = np.mod(u + (0.5 if case.get("variant") == "half_turn" else 0.0), 1.0)
        uv = np.stack([u, np.arccos(np.clip(n[:, 2], -1, 1)) / np.pi], 1)
        return x, n, uv, (disc > 0) & (t > 0)
    t = -o[1] / d[:, 1]
    x = o + t[:, None] * d
    sx, _, sz = case["size"]
    ok = (t > 0) & (np.abs(x[:, 0]) <= sx) & (np.abs(x[:, 2]) <= sz)
    uv = np.stack([x[:, 0] / sx, x[:, 2] / sz, np.ones(len(x))], 1) @ case["uv_map"]
    return x, np.tile([0.0, 1.0, 0.0], (len(x), 1)), uv, ok


def _albedo(case, uv):
    du, dv = case["delta"]
    su, sv = case["scale"]
    if case.get("variant") == "uv_delta":
        cells = np.floor((uv[:, 0] - du) / su) + np.floor((uv[:, 1] - dv) / sv)
    else:
        cells = np.floor(uv[:, 0] / su - du) + np.floor(uv[:, 1] / sv - dv)
    return np.where((np.mod(cells, 2) == 0)[:, None], case["value1"], case["value2"])


def pixel_mean(case, n=40_000_000, seed=1, chunk=1_000_000):
    """(mean, standard error) of the pixel's luminance over `n` uniform image-plane positions."""
    rng = np.random.default_rng(seed)
    o = case["origin"]
    fwd = case["target"] - o
    fwd /= np.linalg.norm(fwd)
    left = np.cross(case["up"], fwd)
    left /= np.linalg.norm(left)
    up = np.cross(fwd, left)
    h = np.tan(np.radians(case["fov"]) / 2)
    s1 = s2 = 0.0
    for start in range(0, n, chunk):
        m = min(chunk, n - start)
        a, b = rng.uniform(-h, h, (2, m))
        d = fwd + a[:, None] * left + b[:, None] * up
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        x, nrm, uv, hit = _hits(case, d)
        w = case["light"] - x
        d2 = (w * w).sum(1)
        cos = np.maximum((nrm * w).sum(1) / np.sqrt(d2), 0.0)
        rgb = _albedo(case, uv) / np.pi * case["power"] / (4 * np.pi) * (cos / d2)[:, None]
        f = np.where(hit, rgb @ LUMINANCE, 0.0)
        s1, s2 = s1 + f.sum(), s2 + (f * f).sum()
    mean = s1 / n
    return mean, np.sqrt(max(s2 / n - mean * mean, 0.0) / n)


if __name__ == "__main__":
    rays = int(float(sys.argv[1])) if len(sys.argv) > 1 else 40_000_000
    refs, cases = read_cases()
    for i, (ref, case) in enumerate(zip(refs, cases), 1):
        mean, se = pixel_mean(case, rays)
        line = f"{i}. {case['shape']}: {mean:.6f} ± {se:.1e} ({se / mean:.1e} relative; file {ref:g})"
        variants = (("uv_delta",) if np.any(case["delta"]) else ()) + (
            ("no_wrap", "half_turn") if case["shape"] == "sphere" else ())
        for variant in variants:
            line += f"; {variant} {pixel_mean(dict(case, variant=variant), rays // 10)[0]:.4f}"
        print(line, flush=True)
