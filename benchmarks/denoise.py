"""Denoising measured: relMSE of the denoised image at 4, 16 and 64 spp against the raw image's, and the spp the raw
image needs to reach the same relMSE.

    python benchmarks/denoise.py [--res 128] [--reference-spp 512] [--json OUT]

Scenes: the Cornell twin of benchmarks/vs_mitsuba.py (mirror and glass spheres), our Veach MIS scene, our glass
scene and the Mitsuba showcase (scenes/), all at --res on their longer side. Per scene: a reference (uniform,
--reference-spp, its own seed; relMSE less its expected share, as benchmarks/adaptive.py does); raw renders at 4, 8,
... 64 spp; renders with the feature AOVs at 4, 16, 64 spp, denoised (Film.denoised: OIDN's RT filter, HDR, albedo
and normal guides prefiltered). For each denoised image: its relMSE (all pixels and without the 0.1 % worst), the
render seconds with the AOVs, the denoiser's seconds, and the raw spp with the same relMSE, read off the raw curve in
log-log (beyond 64 spp: relMSE ~ 1/spp from 64). Written to benchmarks/results/denoise-<date>.json and printed.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import vs_mitsuba as vm  # noqa: E402
from adaptive import corrected_relmse, time_to, write_results  # noqa: E402  (relMSE less the reference's share, ...)

ROOT = Path(__file__).resolve().parents[1]
SCENES = {"veach_mis": "mis/mis_path_mis.xml", "glass": "glass/glass_path_mis.xml",
          "showcase": "mitsuba/showcase.xml"}


def bench_scene(name, xml: Path, res: int, ref_spp: int, say) -> dict:
    import clrender
    from clrender.renderer import Renderer

    scene = clrender.load_scene(xml)
    w, h = scene.width, scene.height
    scene.camera.width, scene.camera.height = res * w // max(w, h), res * h // max(w, h)
    plain, feat = Renderer(scene), Renderer(scene, feature_aovs=True)
    plain.render(spp=1)
    feat.render(spp=1)
    say(f"{name}: reference, {ref_spp} spp")
    rf = plain.render(spp=ref_spp, seed=12345)
    ref, ref_var = rf.image.astype(np.float64), rf.variance()
    raw = []
    s = 4
    while s <= 64:
        f = plain.render(spp=s, seed=7)
        raw.append({"spp": s, "seconds": f.stats.seconds, **corrected_relmse(f.image, ref, ref_var)})
        s *= 2
    out = {"width": plain.width, "height": plain.height, "raw": raw, "denoised": []}
    for s in (4, 16, 64):
        f = feat.render(spp=s, seed=7)
        t0 = time.perf_counter()
        img = f.denoised()
        secs = time.perf_counter() - t0
        row = {"spp": s, "render_seconds": f.stats.seconds, "denoise_seconds": secs,
               **corrected_relmse(img, ref, ref_var)}
        for metric in ("relmse", "relmse_robust"):
            row[f"raw_spp_same_{metric}"] = time_to([(p["spp"], p[metric]) for p in raw], row[metric])
        out["denoised"].append(row)
        say(f"{name}: {s} spp denoised: relMSE {row['relmse']:.4g} = raw at {row['raw_spp_same_relmse']:.0f} spp")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--reference-spp", type=int, default=512)
    ap.add_argument("--json", help="default: benchmarks/results/denoise-<date>.json")
    a = ap.parse_args(argv)
    say = lambda m: print(f"denoise: {m}", file=sys.stderr, flush=True)  # noqa: E731
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        files = vm.write_twin(vm.TWINS["cornell_spheres"](d, 64, a.res), d)
        results["cornell_spheres"] = bench_scene("cornell_spheres", files["clrender"], a.res, a.reference_spp, say)
        for name, rel in SCENES.items():
            results[name] = bench_scene(name, ROOT / "scenes" / rel, a.res, a.reference_spp, say)
    path = write_results("denoise", a.json, results, res=a.res, reference_spp=a.reference_spp)
    print(f"{'scene':16} {'size':>8} {'spp':>4} {'raw relMSE':>10} {'denoised':>9} {'raw spp same':>12} "
          f"{'robust: raw spp':>15} {'render s':>8} {'denoise s':>9}")
    for name, r in results.items():
        raw = {p["spp"]: p for p in r["raw"]}
        for row in r["denoised"]:
            print(f"{name:16} {r['width']:>4}x{r['height']:<3} {row['spp']:4d} {raw[row['spp']]['relmse']:10.4g} "
                  f"{row['relmse']:9.4g} {row['raw_spp_same_relmse']:12.0f} {row['raw_spp_same_relmse_robust']:15.0f} "
                  f"{row['render_seconds']:8.2f} {row['denoise_seconds']:9.2f}")
    print(f"wrote {path}", file=sys.stderr)


if __name__ == "__main__":
    main()
