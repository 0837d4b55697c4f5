"""Development tool: evaluate Mitsuba 3's plastic, roughplastic and composite BSDFs (scalar_rgb) at a fixed set of
direction pairs and write the values the default test run compares clrender with (tests/bsdfs/coated_common.py).

    pip install mitsuba==3.9.1      # dev only, never a dependency of clrender
    python tests/mitsuba/bsdf_values/make_coated_values.py

Each case is a Mitsuba plugin dict (the test builds the clrender BSDF from the same dict); each JSON file holds the
cases, the direction pairs (local frame, z = normal) and Mitsuba's eval (f times |cos theta_o|, as Mitsuba
returns it) and pdf per pair.
"""
import json
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def directions():
    """(wi, wo) pairs: wi at several elevations (front, and the back for twosided), wo on a grid over the sphere
    plus near the mirror direction, where the glossy lobes are."""
    pairs = []
    rng = np.random.default_rng(14)
    for th_i in (0.0, 25.0, 55.0, 80.0):
        t = np.radians(th_i)
        wi = np.array([np.sin(t), 0.0, np.cos(t)])
        for th_o in (5.0, 30.0, 50.0, 70.0, 85.0):
            for ph_o in (0.0, 100.0, 180.0, 250.0):
                a, p = np.radians(th_o), np.radians(ph_o)
                pairs.append((wi, np.array([np.sin(a) * np.cos(p), np.sin(a) * np.sin(p), np.cos(a)])))
        for _ in range(6):   # around the mirror direction
            wo = np.array([-wi[0], 0.0, wi[2]]) + rng.normal(scale=0.15, size=3)
            wo[2] = abs(wo[2]) + 0.02
            pairs.append((wi, wo / np.linalg.norm(wo)))
    back = [(wi * np.array([1, 1, -1]), wo * np.array([1, 1, -1])) for wi, wo in pairs[::3]]
    return pairs + back


def rgb(*v):
    return {"type": "rgb", "value": list(v)}


PLASTIC = {
    "plastic-default": {"type": "plastic"},
    "plastic-colour": {"type": "plastic", "diffuse_reflectance": rgb(0.2, 0.5, 0.8), "int_ior": 1.7},
    "plastic-nonlinear": {"type": "plastic", "diffuse_reflectance": rgb(0.9, 0.5, 0.1), "nonlinear": True,
                          "specular_reflectance": rgb(0.7, 0.8, 0.9)},
    "plastic-named-ior": {"type": "plastic", "int_ior": "bk7", "ext_ior": "water"},
}
ROUGH = {}
for dist in ("beckmann", "ggx"):
    for alpha in (0.05, 0.2, 0.6):
        # clrender samples Beckmann normals from D cos (Mitsuba: visible normals); with sample_visible false both
        # use D cos, so the pdfs compare too
        ROUGH[f"roughplastic-{dist}-{alpha:g}"] = {"type": "roughplastic", "distribution": dist, "alpha": alpha,
                                                  "diffuse_reflectance": rgb(0.3, 0.6, 0.2),
                                                  "sample_visible": dist == "ggx"}
ROUGH["roughplastic-nonlinear-ior"] = {"type": "roughplastic", "alpha": 0.3, "int_ior": 2.0, "nonlinear": True,
                                       "diffuse_reflectance": rgb(0.8, 0.4, 0.9),
                                       "specular_reflectance": rgb(0.5, 0.9, 0.7)}
ROUGH["roughplastic-default"] = {"type": "roughplastic"}
COMPOSITES = {
    "twosided-one": {"type": "twosided", "a": {"type": "roughplastic", "alpha": 0.3, "sample_visible": False}},
    "twosided-two": {"type": "twosided", "a": {"type": "roughplastic", "alpha": 0.3, "distribution": "ggx"},
                     "b": {"type": "plastic", "diffuse_reflectance": rgb(0.1, 0.8, 0.3)}},
    "blend": {"type": "blendbsdf", "weight": 0.3, "a": {"type": "roughplastic", "alpha": 0.1, "distribution": "ggx"},
              "b": {"type": "plastic", "diffuse_reflectance": rgb(0.9, 0.1, 0.1)}},
    "mask": {"type": "mask", "opacity": 0.35, "a": {"type": "roughplastic", "alpha": 0.4, "distribution": "ggx"}},
    "mask-beckmann": {"type": "mask", "opacity": 0.8, "a": {"type": "roughplastic", "alpha": 0.25,
                                                            "sample_visible": False}},
    "mask-twosided-blend": {"type": "mask", "opacity": 0.7, "a": {"type": "twosided", "a": {
        "type": "blendbsdf", "weight": 0.6, "a": {"type": "plastic"},
        "b": {"type": "roughplastic", "alpha": 0.2, "distribution": "ggx"}}}},
}


def evaluate(cases, pairs):
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    out = {"mitsuba_version": mi.__version__, "variant": "scalar_rgb",
           "wi": [list(map(float, wi)) for wi, _ in pairs], "wo": [list(map(float, wo)) for _, wo in pairs],
           "cases": {}}
    ctx = mi.BSDFContext()
    for name, d in cases.items():
        bsdf = mi.load_dict(d)
        vals, pdfs = [], []
        for wi, wo in pairs:
            si = mi.SurfaceInteraction3f()
            si.p = [0, 0, 0]
            si.n = [0, 0, 1]
            si.sh_frame = mi.Frame3f(si.n)
            si.uv = [0.5, 0.5]
            si.wi = mi.Vector3f(*wi)
            v = bsdf.eval(ctx, si, mi.Vector3f(*wo))
            vals.append([float(v[0]), float(v[1]), float(v[2])])
            pdfs.append(float(bsdf.pdf(ctx, si, mi.Vector3f(*wo))))
        out["cases"][name] = {"dict": d, "eval": vals, "pdf": pdfs}
    return out


def main():
    pairs = directions()
    for fname, cases in (("plastic.json", PLASTIC), ("roughplastic.json", ROUGH), ("composites.json", COMPOSITES)):
        data = evaluate(cases, pairs)
        (HERE / fname).write_text(json.dumps(data, separators=(",", ":")) + "\n")
        print(fname, len(cases), "cases x", len(pairs), "pairs")


if __name__ == "__main__":
    main()
