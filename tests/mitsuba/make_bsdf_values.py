"""Reference values of Mitsuba 3's conductor and dielectric BSDFs, evaluated by Mitsuba itself (development only:
`pip install mitsuba==3.9.1`; nothing at install, run or test time needs it).

    python tests/mitsuba/make_bsdf_values.py            # writes tests/mitsuba/bsdf_values/conductors_dielectrics.json
    python tests/mitsuba/make_bsdf_values.py --presets  # prints conductor presets as clrender/bsdfs/conductor.py has them

Each case is one BSDF, given as the (tag, value) properties clrender's registry takes, evaluated at the file's
directions (wi: (13, 3); wo: (13, 16, 3), per wi). Glossy BSDFs: f = eval/cos_o (Mitsuba's eval includes the
cosine) at each (wi, wo). Delta BSDFs: for each wi, the reflection (sample1 = 0) and
transmission (sample1 -> 1) samples: direction, weight and probability (Mitsuba's bs.pdf of a delta lobe).
tests/bsdfs/test_<name>.py (through tests/bsdfs/mitsuba_values.py) compares clrender's kernels with these values.
"""
import json
import sys
from pathlib import Path

import numpy as np

from clrender.testing.mitsuba_dict import rounded

OUT = Path(__file__).parent / "bsdf_values" / "conductors_dielectrics.json"

GLOSSY = [
    ("roughconductor", {}),
    ("roughconductor", {"material": ("string", "Au"), "alpha": ("float", 0.3)}),
    ("roughconductor", {"material": ("string", "Cu"), "distribution": ("string", "ggx"), "alpha": ("float", 0.15)}),
    ("roughconductor", {"distribution": ("string", "ggx"), "alpha_u": ("float", 0.05), "alpha_v": ("float", 0.4),
                        "eta": ("color", (1.2, 0.9, 0.4)), "k": ("color", (3.0, 2.5, 2.0)),
                        "specular_reflectance": ("color", (0.9, 0.7, 0.5))}),
    ("roughconductor", {"alpha_u": ("float", 0.4), "alpha_v": ("float", 0.1), "material": ("string", "Al"),
                        "sample_visible": ("boolean", False)}),
    ("roughconductor", {"material": ("string", "a-C"), "alpha": ("float", 0.7)}),
    ("roughdielectric", {}),
    ("roughdielectric", {"alpha": ("float", 0.3), "int_ior": ("string", "diamond")}),
    ("roughdielectric", {"distribution": ("string", "ggx"), "alpha": ("float", 0.2), "int_ior": ("float", 1.33),
                         "ext_ior": ("float", 1.0), "specular_transmittance": ("color", (0.8, 0.9, 1.0))}),
    ("roughdielectric", {"distribution": ("string", "ggx"), "alpha_u": ("float", 0.05), "alpha_v": ("float", 0.3),
                         "int_ior": ("string", "water"), "ext_ior": ("string", "bk7"),
                         "specular_reflectance": ("color", (0.5, 0.6, 0.7))}),
    ("roughdielectric", {"alpha": ("float", 0.6), "int_ior": ("float", 1.7)}),
]
DELTA = [
    ("conductor", {}),
    ("conductor", {"material": ("string", "Au")}),
    ("conductor", {"material": ("string", "Cr"), "specular_reflectance": ("color", (0.5, 0.8, 1.0))}),
    ("conductor", {"eta": ("color", (0.2, 0.9, 1.1)), "k": ("color", (3.9, 2.4, 2.1))}),
    ("dielectric", {}),
    ("dielectric", {"int_ior": ("string", "diamond"), "specular_transmittance": ("color", (0.5, 0.7, 0.9))}),
    ("dielectric", {"int_ior": ("float", 1.33), "ext_ior": ("string", "pyrex"),
                    "specular_reflectance": ("color", (0.9, 0.8, 0.7))}),
    ("thindielectric", {}),
    ("thindielectric", {"int_ior": ("string", "diamond"), "specular_transmittance": ("color", (0.5, 0.7, 0.9))}),
]


def _dirs(rng, n, lower=False):
    d = rng.normal(size=(n, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.02
    if lower:
        d[: n // 2, 2] *= -1
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def directions():
    """wi above and below; wo on both sides, with some near the mirror/refraction peak and grazing angles."""
    rng = np.random.default_rng(2026)
    wi = np.concatenate([_dirs(rng, 10, lower=True), [[0, 0, 1.0], [0.999, 0, 0.0447], [0.6, 0.0, -0.8]]])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    wo = []
    for w in wi:
        around = w * np.array([-1, -1, 1]) + rng.normal(scale=0.15, size=(6, 3))
        wo.append(np.concatenate([_dirs(rng, 10, lower=True), around / np.linalg.norm(around, axis=1, keepdims=True)]))
    return wi, np.array(wo)


def to_mitsuba(kind, props):
    d = {"type": kind}
    for name, (tag, value) in props.items():
        d[name] = {"type": "rgb", "value": list(value)} if tag == "color" else value
    return d


def main(argv):
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    if "--presets" in argv:
        from clrender.bsdfs.conductor import MATERIALS

        for name in MATERIALS:
            p = mi.traverse(mi.load_dict({"type": "conductor", "material": name}))
            print(f'    "{name}": ({tuple(round(float(x), 6) for x in p["eta.value"])}, '
                  f'{tuple(round(float(x), 6) for x in p["k.value"])}),')
        return
    ctx = mi.BSDFContext()
    wi_all, wo_all = directions()
    cases = []

    def interaction(wi):
        si = mi.SurfaceInteraction3f()
        si.p = mi.Point3f(0, 0, 0)
        si.n = mi.Normal3f(0, 0, 1)
        si.sh_frame = mi.Frame3f(si.n)
        si.uv = mi.Point2f(0.5, 0.5)
        si.wi = mi.Vector3f(*wi)
        return si

    for kind, props in GLOSSY:
        bsdf = mi.load_dict(to_mitsuba(kind, props))
        f = []
        for wi, wos in zip(wi_all, wo_all):
            si = interaction(wi)
            row = []
            for wo in wos:
                v = bsdf.eval(ctx, si, mi.Vector3f(*wo))
                row.append([float(c) / abs(wo[2]) for c in v])
            f.append(row)
        cases.append({"type": kind, "props": props, "f": f})
    for kind, props in DELTA:
        bsdf = mi.load_dict(to_mitsuba(kind, props))
        events = []
        for wi in wi_all:
            si = interaction(wi)
            ev = {}
            for label, s1 in (("reflect", 0.0), ("transmit", 1.0 - 1e-7)):
                bs, w = bsdf.sample(ctx, si, s1, mi.Point2f(0.5, 0.5))
                wo = [float(c) for c in bs.wo]
                refl = wo[2] * wi[2] > 0
                if float(bs.pdf) > 0 and (refl == (label == "reflect")) and any(float(c) != 0 for c in w):
                    ev[label] = {"wo": wo, "weight": [float(c) for c in w], "prob": float(bs.pdf),
                                 "eta": float(bs.eta)}
            events.append(ev)
        cases.append({"type": kind, "props": props, "events": events})
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(rounded({"mitsuba_version": mi.__version__, "variant": "scalar_rgb",
                                       "wi": wi_all.tolist(), "wo": wo_all.tolist(), "cases": cases}), separators=(",", ":")))
    print(f"wrote {OUT} ({len(cases)} cases)")


if __name__ == "__main__":
    main(sys.argv[1:])
