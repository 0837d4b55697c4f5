"""Development tool: evaluate Mitsuba 3's principled and principledthin BSDFs at fixed direction pairs and write the
values the default test run compares clrender with (tests/bsdfs/test_principled.py, test_principledthin.py):
principled.json, principledthin.json.

    pip install mitsuba==3.9.1      # dev only, never a dependency of clrender
    python tests/mitsuba/bsdf_values/make_principled_values.py

Each case is a Mitsuba plugin dict (the test builds the clrender BSDF from the same dict) and the variant it is
evaluated in: scalar_rgb, except where Mitsuba's variants disagree (scalar_rgb adds sheen only where the diffuse lobe
is on, so not at spec_trans = 1; the vectorised variants, which render the twin references, add it there too:
llvm_ad_rgb for that case). The file holds the direction pairs (local frame, z = normal; wi on both sides, wo over
the sphere and near the mirror and refraction directions) and, per case, Mitsuba's eval (f |cos theta_o|, as
Mitsuba returns it) and pdf per pair.
"""
import json
import os
from pathlib import Path

import numpy as np

from clrender.testing.directions import refracted

HERE = Path(__file__).resolve().parent
LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"


def directions():
    """(wi, wo) pairs: wi at several elevations above and below; wo on a grid over the sphere plus near the mirror
    and (eta 1.5) refraction directions, where the glossy lobes are."""
    pairs = []
    rng = np.random.default_rng(31)
    for side in (1, -1):
        for th_i in ((0.0, 30.0, 60.0, 82.0) if side > 0 else (10.0, 45.0, 75.0)):
            t = np.radians(th_i)
            wi = np.array([np.sin(t) * 0.8, np.sin(t) * 0.6, side * np.cos(t)])
            for th_o in (5.0, 35.0, 60.0, 85.0, 100.0, 130.0, 170.0):
                for ph_o in (0.0, 110.0, 200.0, 290.0):
                    a, p = np.radians(th_o), np.radians(ph_o)
                    pairs.append((wi, np.array([np.sin(a) * np.cos(p), np.sin(a) * np.sin(p), side * np.cos(a)])))
            targets = [wi * np.array([-1, -1, 1])]
            r = refracted(wi, 1.5)
            if r is not None:
                targets.append(r)
            for d in targets:
                for scale in (0.12,) * 5 + (0.015,) * 3:   # the wide lobes, and the sharp ones (clearcoat, roughness 0.05)
                    wo = d + rng.normal(scale=scale, size=3)
                    pairs.append((wi, wo / np.linalg.norm(wo)))
    return pairs


def rgb(*v):
    return {"type": "rgb", "value": list(v)}


CASES = {
    "default": {"type": "principled"},
    "metal-tinted": {"type": "principled", "base_color": rgb(0.9, 0.6, 0.2), "metallic": 0.8, "roughness": 0.3,
                     "spec_tint": 0.5},
    "metal-full-smooth": {"type": "principled", "base_color": rgb(0.95, 0.9, 0.85), "metallic": 1.0,
                          "roughness": 0.1},
    "glass-eta": {"type": "principled", "base_color": rgb(0.9, 0.8, 0.6), "spec_trans": 0.7, "roughness": 0.2,
                  "eta": 1.45},
    "glass-full-specular": {"type": "principled", "spec_trans": 1.0, "roughness": 0.5, "specular": 0.3},
    "sheen-clearcoat": {"type": "principled", "base_color": rgb(0.2, 0.4, 0.7), "roughness": 0.6, "sheen": 0.6,
                        "sheen_tint": 0.4, "clearcoat": 0.8, "clearcoat_gloss": 0.6},
    "anisotropic": {"type": "principled", "base_color": rgb(0.5, 0.5, 0.3), "anisotropic": 0.7, "roughness": 0.4,
                    "metallic": 0.3, "spec_tint": 0.2},
    "flatness-rough": {"type": "principled", "base_color": rgb(0.7, 0.3, 0.3), "flatness": 0.5, "roughness": 0.9},
    "everything": {"type": "principled", "base_color": rgb(0.3, 0.8, 0.5), "roughness": 0.35, "anisotropic": 0.3,
                   "metallic": 0.2, "spec_trans": 0.4, "specular": 0.7, "spec_tint": 0.3, "sheen": 0.3,
                   "sheen_tint": 0.7, "flatness": 0.2, "clearcoat": 0.5, "clearcoat_gloss": 0.3,
                   "main_specular_sampling_rate": 0.7, "clearcoat_sampling_rate": 2.0,
                   "diffuse_reflectance_sampling_rate": 0.5},
    "smooth-transmissive-clearcoat": {"type": "principled", "roughness": 0.05, "spec_trans": 0.5, "clearcoat": 1.0,
                                      "clearcoat_gloss": 0.9, "eta": 1.33},
    "eta-below-one": {"type": "principled", "spec_trans": 0.6, "eta": 0.8, "roughness": 0.3},
    "zero-specular-transmissive": {"type": "principled", "spec_trans": 0.5, "specular": 0.0, "roughness": 0.4},
    "zero-roughness-metal": {"type": "principled", "metallic": 0.6, "roughness": 0.0, "base_color": rgb(0.5, 0.9, 1)},
    # a reflective material as Blender's exporter writes it: twosided around principled, specular (not eta)
    "blender-twosided": {"type": "twosided", "bsdf": {"type": "principled", "base_color": rgb(0.1, 0.3, 0.8),
                                                      "roughness": 0.45, "metallic": 0.1, "specular": 0.5,
                                                      "spec_tint": 0.0, "spec_trans": 0.0, "anisotropic": 0.0,
                                                      "sheen": 0.0, "sheen_tint": 0.5, "clearcoat": 0.3,
                                                      "clearcoat_gloss": 0.2}},
    # white: Burley's model returns more than arrives here (the albedos below show it, Mitsuba's as ours)
    "white-rough": {"type": "principled", "base_color": rgb(1, 1, 1), "roughness": 1.0},
    "white-sheen-clearcoat": {"type": "principled", "base_color": rgb(1, 1, 1), "roughness": 0.2, "sheen": 1.0,
                              "clearcoat": 1.0},
}
THIN = {
    "thin-default": {"type": "principledthin"},
    "thin-doc": {"type": "principledthin", "base_color": rgb(0.7, 0.1, 0.1), "roughness": 0.15, "spec_tint": 0.1,
                 "anisotropic": 0.5, "spec_trans": 0.8, "diff_trans": 0.3, "eta": 1.33},
    "thin-leaf": {"type": "principledthin", "base_color": rgb(0.2, 0.6, 0.1), "roughness": 0.6, "spec_trans": 0.2,
                  "diff_trans": 1.2, "sheen": 0.5, "sheen_tint": 0.6, "flatness": 0.4, "eta": 1.4},
    "thin-smooth-rates": {"type": "principledthin", "roughness": 0.1, "spec_trans": 0.6, "diff_trans": 0.5,
                          "specular_reflectance_sampling_rate": 2.0, "specular_transmittance_sampling_rate": 0.5,
                          "diffuse_reflectance_sampling_rate": 0.7, "diffuse_transmittance_sampling_rate": 1.5},
    "thin-only-specular": {"type": "principledthin", "spec_trans": 1.0, "roughness": 0.3, "eta": 1.7,
                           "base_color": rgb(0.9, 0.9, 0.5), "spec_tint": 0.5},
    "thin-white-diffuse-transmission": {"type": "principledthin", "base_color": rgb(1, 1, 1), "diff_trans": 2.0},
}
# Mitsuba's variants disagree here (see the docstring): evaluated with the vectorised one
VECTORISED = {
    "glass-sheen": {"type": "principled", "spec_trans": 1.0, "sheen": 0.8, "sheen_tint": 0.5,
                    "base_color": rgb(0.6, 0.7, 0.9), "roughness": 0.3},
}


def evaluate(mi, variant, cases, pairs):
    mi.set_variant(variant)
    ctx = mi.BSDFContext()
    out = {}
    wi = np.array([p[0] for p in pairs])
    wo = np.array([p[1] for p in pairs])
    for name, d in cases.items():
        bsdf = mi.load_dict(d)
        if variant == "scalar_rgb":
            vals, pdfs = [], []
            for a, b in pairs:
                si = mi.SurfaceInteraction3f()
                si.p, si.n, si.uv = [0, 0, 0], [0, 0, 1], [0.5, 0.5]
                si.sh_frame = mi.Frame3f(si.n)
                si.wi = mi.Vector3f(*a)
                v = bsdf.eval(ctx, si, mi.Vector3f(*b))
                vals.append([float(v[0]), float(v[1]), float(v[2])])
                pdfs.append(float(bsdf.pdf(ctx, si, mi.Vector3f(*b))))
        else:
            si = mi.SurfaceInteraction3f()
            n = len(pairs)
            si.p = mi.Point3f(np.zeros(n), np.zeros(n), np.zeros(n))
            si.n = mi.Normal3f(np.zeros(n), np.zeros(n), np.ones(n))
            si.sh_frame = mi.Frame3f(si.n)
            si.uv = mi.Point2f(np.full(n, 0.5), np.full(n, 0.5))
            si.wi = mi.Vector3f(wi[:, 0], wi[:, 1], wi[:, 2])
            w = mi.Vector3f(wo[:, 0], wo[:, 1], wo[:, 2])
            vals = np.array(bsdf.eval(ctx, si, w)).T.tolist()
            pdfs = np.array(bsdf.pdf(ctx, si, w)).tolist()
        out[name] = {"dict": d, "variant": variant, "eval": vals, "pdf": pdfs}
    return out


ALBEDO_WI = ((0.0, 1), (45.0, 1), (80.0, 1), (45.0, -1))
ALBEDO_N = 1 << 18


def albedos(mi, cases):
    """Per case, at each of ALBEDO_WI (theta, side): the mean and the standard error of Mitsuba's sample weight
    (radiance transport: refractions carry 1/eta^2), i.e. the albedo, over ALBEDO_N samples (llvm_ad_rgb)."""
    mi.set_variant("llvm_ad_rgb")
    ctx = mi.BSDFContext()
    out = {}
    for name, d in cases.items():
        bsdf = mi.load_dict(d)
        sampler = mi.load_dict({"type": "independent"})
        sampler.seed(7, ALBEDO_N)
        res = []
        for th, side in ALBEDO_WI:
            t = np.radians(th)
            si = mi.SurfaceInteraction3f()
            si.n = mi.Normal3f(0, 0, 1)
            si.sh_frame = mi.Frame3f(si.n)
            si.wi = mi.Vector3f(float(np.sin(t)), 0.0, float(side * np.cos(t)))
            bs, w = bsdf.sample(ctx, si, sampler.next_1d(), sampler.next_2d())
            w = np.array(w)[0].astype(np.float64)
            res.append([float(w.mean()), float(w.std() / np.sqrt(len(w)))])
        out[name] = res
    return out


def main():
    if "DRJIT_LIBLLVM_PATH" not in os.environ and Path(LLVM).is_file():
        os.environ["DRJIT_LIBLLVM_PATH"] = LLVM
    import mitsuba as mi

    pairs = directions()
    for fname, scalar, vectorised in (("principled.json", CASES, VECTORISED), ("principledthin.json", THIN, {})):
        cases = evaluate(mi, "scalar_rgb", scalar, pairs)
        cases.update(evaluate(mi, "llvm_ad_rgb", vectorised, pairs))
        for name, a in albedos(mi, {**scalar, **vectorised}).items():
            cases[name]["albedo"] = a
        data = {"mitsuba_version": mi.__version__, "wi": [list(map(float, a)) for a, _ in pairs],
                "albedo_wi": [list(x) for x in ALBEDO_WI],
                "wo": [list(map(float, b)) for _, b in pairs], "cases": cases}
        (HERE / fname).write_text(json.dumps(data, separators=(",", ":")) + "\n")
        print(fname, len(cases), "cases x", len(pairs), "pairs")


if __name__ == "__main__":
    main()
