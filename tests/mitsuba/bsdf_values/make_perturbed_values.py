"""Development tool: evaluate Mitsuba 3's normalmap and bumpmap (scalar_rgb) at fixed surface points and direction
pairs, and write the values tests/bsdfs/perturbed_common.py compares clrender with (perturbed.json), with the small
textures they read (perturbed_*.png, made here from formulas).

    pip install mitsuba==3.9.1      # dev only, never a dependency of clrender
    python tests/mitsuba/bsdf_values/make_perturbed_values.py

Each case is a Mitsuba plugin dict (texture filenames relative to this folder; the test builds the clrender BSDF from
the same dict). Each surface point has a uv, Mitsuba's interaction geometry (a shading frame whose first axis
follows dp/du, a geometric normal near the shading normal, dp/du and dp/dv) and wi; the file holds that geometry in
the local frame (dp/du, dp/dv, the geometric normal; and dp/du in world space) as clrender's BSDF query carries it,
the wo of each pair (local) and Mitsuba's eval (f |cos theta_o|, as it returns it) and pdf; and, for a few bitmaps,
the uv gradient Mitsuba's eval_1_grad gives at random uvs (what bumpmap differentiates).
"""
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[2]))
from clrender.png import encode_png  # noqa: E402
from clrender.testing.mitsuba_dict import rounded  # noqa: E402


def textures():
    """name -> (H, W, 3) uint8: a normal map of bumps and strong tilts (some past the horizon for grazing wi), a
    height field of smooth ripples, and a non-square height image."""
    h, w = 6, 8
    y, x = np.mgrid[0:h, 0:w]
    nx = 0.8 * np.sin(1.3 * x + 0.7 * y)
    ny = 0.6 * np.cos(0.9 * y - 0.4 * x)
    nz = 0.35 + 0.6 * ((x + 2 * y) % 3) / 2
    n = np.stack([nx, ny, nz], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    normals = np.round((n + 1) / 2 * 255).astype(np.uint8)
    hgt = 0.5 + 0.4 * np.sin(0.9 * x) * np.cos(1.1 * y) + 0.08 * x
    height = np.repeat(np.round(np.clip(hgt, 0, 1) * 255).astype(np.uint8)[..., None], 3, -1)
    y2, x2 = np.mgrid[0:5, 0:11]
    colour = np.stack([0.5 + 0.4 * np.sin(x2), 0.5 + 0.4 * np.cos(0.7 * y2 + x2), 0.3 + 0.05 * x2], -1)
    ripple = np.round(np.clip(colour, 0, 1) * 255).astype(np.uint8)
    return {"perturbed_normals.png": normals, "perturbed_height.png": height, "perturbed_ripple.png": ripple}


def bitmap(name, **kw):
    return {"type": "bitmap", "filename": name, **kw}


def rgb(*v):
    return {"type": "rgb", "value": list(v)}


ANISO = {"type": "roughconductor", "distribution": "ggx", "alpha_u": 0.08, "alpha_v": 0.4, "material": "Au"}
NM = bitmap("perturbed_normals.png", raw=True)
CASES = {
    "normalmap-aniso": {"type": "normalmap", "normalmap": NM, "bsdf": ANISO},
    "normalmap-diffuse-noflip": {"type": "normalmap", "normalmap": bitmap("perturbed_normals.png", raw=True,
                                                                          filter_type="nearest"),
                                 "flip_invalid_normals": False, "bsdf": {"type": "diffuse",
                                                                         "reflectance": rgb(0.7, 0.5, 0.3)}},
    "normalmap-roughplastic-noshadow": {"type": "normalmap", "normalmap": NM, "use_shadowing_function": False,
                                        "bsdf": {"type": "roughplastic", "distribution": "ggx", "alpha": 0.3}},
    "normalmap-srgb-roughdielectric": {"type": "normalmap", "normalmap": bitmap("perturbed_normals.png"),
                                       "bsdf": {"type": "roughdielectric", "distribution": "ggx", "alpha": 0.25}},
    "normalmap-rgb": {"type": "normalmap", "normalmap": rgb(0.62, 0.41, 0.9), "bsdf": ANISO},
    "bumpmap-diffuse": {"type": "bumpmap", "height": bitmap("perturbed_height.png", raw=True), "scale": 0.4,
                        "bsdf": {"type": "diffuse"}},
    "bumpmap-aniso-to_uv": {"type": "bumpmap", "arbitrary": bitmap("perturbed_ripple.png", raw=True,
                                                                   wrap_mode="mirror", to_uv="rotate"),
                            "scale": 0.15, "bsdf": ANISO},
    "bumpmap-noflip-noshadow": {"type": "bumpmap", "height": bitmap("perturbed_height.png", raw=True,
                                                                    wrap_mode="clamp"),
                                "scale": 1.5, "flip_invalid_normals": False, "use_shadowing_function": False,
                                "bsdf": {"type": "roughconductor", "alpha": 0.2}},
    "bumpmap-srgb-plastic": {"type": "bumpmap", "t": bitmap("perturbed_ripple.png"), "scale": 0.3,
                             "bsdf": {"type": "roughplastic", "alpha": 0.2, "diffuse_reflectance": rgb(0.2, 0.4, 0.7)}},
    "twosided-normalmap": {"type": "twosided", "bsdf": {"type": "normalmap", "normalmap": NM,
                                                        "bsdf": {"type": "diffuse"}}},
    "blend-normalmap-bumpmap": {"type": "blendbsdf", "weight": 0.35,
                                "a": {"type": "normalmap", "normalmap": NM, "bsdf": {"type": "diffuse"}},
                                "b": {"type": "bumpmap", "height": bitmap("perturbed_height.png", raw=True),
                                      "scale": 0.6, "bsdf": ANISO}},
    "normalmap-of-bumpmap": {"type": "normalmap", "normalmap": NM,
                             "bsdf": {"type": "bumpmap", "height": bitmap("perturbed_height.png", raw=True),
                                      "scale": 0.5, "bsdf": ANISO}},
}
#: bitmaps whose uv gradient (eval_1_grad) is recorded at random uvs: every wrap mode, a to_uv that turns a
#: non-square image, an sRGB-decoded colour image (the luminance is differentiated), and `nearest` (no gradient)
GRADIENTS = {
    "repeat": bitmap("perturbed_height.png", raw=True),
    "mirror-to_uv": bitmap("perturbed_ripple.png", raw=True, wrap_mode="mirror", to_uv="rotate"),
    "clamp-srgb": bitmap("perturbed_ripple.png", wrap_mode="clamp"),
    "nearest": bitmap("perturbed_height.png", raw=True, filter_type="nearest"),
}
#: to_uv transforms by name (a string in a dict above): the test builds the same 4x4 matrix
TO_UV = {"rotate": [[1.2 * np.cos(0.5), -0.7 * np.sin(0.5), 0, 0.1], [1.2 * np.sin(0.5), 0.7 * np.cos(0.5), 0, -0.3],
                    [0, 0, 1, 0], [0, 0, 0, 1]]}


def points(n=14, n_wo=14):
    """Surface points (uv, world geometry, wi local) and wo per point, reproducibly."""
    rng = np.random.default_rng(99)
    out = []
    for k in range(n):
        nn = rng.normal(size=3)
        nn /= np.linalg.norm(nn)
        dpdu, dpdv = rng.normal(size=3) * rng.uniform(0.5, 3), rng.normal(size=3) * rng.uniform(0.5, 3)
        if np.dot(np.cross(dpdu, dpdv), nn) < 0 and k % 3:
            dpdv = -dpdv                          # mostly a parametrisation that agrees with the normal
        ng = nn + 0.25 * rng.normal(size=3)
        ng /= np.linalg.norm(ng)
        s = dpdu - nn * (nn @ dpdu)
        s /= np.linalg.norm(s)
        frame = np.array([s, np.cross(nn, s), nn])
        wi = rng.normal(size=3)
        wi[2] = abs(wi[2]) * (0.05 if k % 5 == 4 else 1)      # some grazing
        if k in (3, 9):
            wi[2] = -wi[2]                                      # the back side
        wi /= np.linalg.norm(wi)
        wo = rng.normal(size=(n_wo, 3))
        wo[: n_wo // 2, 2] = np.abs(wo[: n_wo // 2, 2]) * np.sign(wi[2])
        wo[-3:] = np.array([-wi[0], -wi[1], wi[2]]) + 0.2 * rng.normal(size=(3, 3))   # near the mirror direction
        wo /= np.linalg.norm(wo, axis=1, keepdims=True)
        out.append(dict(uv=rng.uniform(-0.2, 1.2, 2), frame=frame, ng=ng, dpdu=dpdu, dpdv=dpdv, wi=wi, wo=wo))
    return out


def to_mitsuba(d, mi):
    out = {}
    for k, v in d.items():
        if isinstance(v, dict) and v.get("type") == "rgb":
            out[k] = v
        elif isinstance(v, dict):
            out[k] = to_mitsuba(v, mi)
        elif k == "filename":
            out[k] = str(HERE / v)
        elif k == "to_uv":
            out[k] = mi.ScalarTransform4f(TO_UV[v])
        else:
            out[k] = v
    return out


def main():
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    for name, img in textures().items():
        (HERE / name).write_bytes(encode_png(img))
    ctx = mi.BSDFContext()
    pts = points()
    cases = {}
    for name, d in CASES.items():
        bsdf = mi.load_dict(to_mitsuba(d, mi))
        rows = []
        for p in pts:
            si = mi.SurfaceInteraction3f()
            si.p = mi.Point3f(0, 0, 0)
            si.n = mi.Normal3f(*p["ng"])
            si.sh_frame = mi.Frame3f(*(mi.Vector3f(*v) for v in p["frame"]))
            si.dp_du, si.dp_dv = mi.Vector3f(*p["dpdu"]), mi.Vector3f(*p["dpdv"])
            si.uv = mi.Point2f(*p["uv"])
            si.wi = mi.Vector3f(*p["wi"])
            ev, pdf = [], []
            for wo in p["wo"]:
                v, pd = bsdf.eval_pdf(ctx, si, mi.Vector3f(*wo))
                ev.append([float(c) for c in v])
                pdf.append(float(pd))
            rows.append({"eval": ev, "pdf": pdf})
        cases[name] = {"dict": d, "points": rows}
    rng = np.random.default_rng(7)
    grads = {}
    for name, d in GRADIENTS.items():
        tex = mi.load_dict(to_mitsuba(d, mi))
        uvs = rng.uniform(-1.5, 2.5, (40, 2))
        g = []
        for uv in uvs:
            si = mi.SurfaceInteraction3f()
            si.uv = mi.Point2f(*uv)
            g.append([float(c) for c in tex.eval_1_grad(si)])
        grads[name] = {"dict": d, "uv": uvs.tolist(), "grad": g}
    F = [p["frame"] for p in pts]
    data = {"mitsuba_version": mi.__version__, "variant": "scalar_rgb", "to_uv": TO_UV,
            "points": [{"uv": p["uv"].tolist(), "wi": p["wi"].tolist(), "wo": p["wo"].tolist(),
                        "geometry": [(f @ p["dpdu"]).tolist(), (f @ p["dpdv"]).tolist(), (f @ p["ng"]).tolist(),
                                     p["dpdu"].tolist()]} for p, f in zip(pts, F)],
            "cases": cases, "gradients": grads}

    (HERE / "perturbed.json").write_text(json.dumps(rounded(data), separators=(",", ":")))
    print(f"wrote {HERE / 'perturbed.json'} ({len(cases)} cases x {len(pts)} points)")


if __name__ == "__main__":
    main()
