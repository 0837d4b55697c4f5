"""The splatting film against filter importance sampling: noise per pixel at equal spp, time, and efficiency.

    python benchmarks/splat.py [SCENE.xml ...] [--res 128] [--spp 16] [--renders 6] [--json OUT]

Per scene (default: our Cornell box, the Cornell box with glass and our Veach MIS scene, all with Nori's default
Gaussian filter, rescaled to --res pixels along the longer side), both films render --renders times at --spp with
seeds 1, 2, ... interleaved (splat, sampling, splat, ...). Reported: the mean over pixels of each film's per-pixel
variance across its renders, and the median over pixels (a caustic's or a small light's rare bright samples decide
the mean; a splatting film spreads each over a few pixels, a filter-sampling one leaves it in one, so trimming the
largest pixels would favour the latter); the median render time of each; and the efficiency, 1 / (variance x
time), of splatting over sampling: how many times less time the splatting film needs for the same per-pixel
noise. Both films converge to the same image (tests/test_splat.py); the image means are printed as a check.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ("scenes/cornell/cornell_path_mis.xml", "scenes/glass/glass_path_mis.xml", "scenes/mis/mis_path_mis.xml")


def measure(path: Path, res: int, spp: int, renders: int) -> dict:
    import clrender
    from clrender.renderer import Renderer

    scene = clrender.load_scene(path)
    w, h = scene.width, scene.height
    scene.camera.width, scene.camera.height = max(1, res * w // max(w, h)), max(1, res * h // max(w, h))
    rs = {m: Renderer(scene, reconstruction=m) for m in ("splat", "sampling")}
    for r in rs.values():
        r.render(spp=1)   # first launches outside the timings
    images = {m: [] for m in rs}
    seconds = {m: [] for m in rs}
    for k in range(renders):
        for m, r in rs.items():
            f = r.render(spp=spp, seed=k + 1)
            images[m].append(f.image.astype(np.float64))
            seconds[m].append(f.stats.seconds)
    out = {"scene": str(path), "width": scene.width, "height": scene.height, "spp": spp, "renders": renders}
    var = {m: np.stack(v).var(axis=0, ddof=1).mean(axis=-1) for m, v in images.items()}
    for m in rs:
        out[m] = {"variance": float(var[m].mean()), "variance_median": float(np.median(var[m])),
                  "seconds": float(np.median(seconds[m])), "seconds_all": seconds[m],
                  "mean": float(np.mean(images[m]))}
    t = out["sampling"]["seconds"] / out["splat"]["seconds"]
    out["variance_ratio"] = out["sampling"]["variance"] / out["splat"]["variance"]
    out["variance_ratio_median"] = out["sampling"]["variance_median"] / out["splat"]["variance_median"]
    out["time_ratio"] = t
    out["efficiency"] = out["variance_ratio"] * t
    out["efficiency_median"] = out["variance_ratio_median"] * t
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="*", default=list(DEFAULT))
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--renders", type=int, default=6)
    ap.add_argument("--json")
    a = ap.parse_args(argv)
    from clrender.device.context import get_context

    ctx, _ = get_context(None)
    print(f"device: {ctx.devices[0].platform.name.strip()} / {ctx.devices[0].name.strip()}")
    print("| scene | px | variance sampling / splat (mean; median over pixels) | seconds sampling / splat | "
          "efficiency of splatting (mean; median) | image means sampling / splat |")
    print("|---|---|---|---|---|---|")
    rows = []
    for s in a.scenes:
        p = Path(s) if Path(s).is_absolute() else ROOT / s
        r = measure(p, a.res, a.spp, a.renders)
        rows.append(r)
        print(f"| {p.relative_to(ROOT) if p.is_relative_to(ROOT) else p} | {r['width']}x{r['height']} | "
              f"{r['variance_ratio']:.2f}; {r['variance_ratio_median']:.2f} | "
              f"{r['sampling']['seconds']:.3f} / {r['splat']['seconds']:.3f} | "
              f"{r['efficiency']:.2f}; {r['efficiency_median']:.2f} | "
              f"{r['sampling']['mean']:.4f} / {r['splat']['mean']:.4f} |", flush=True)
    if a.json:
        Path(a.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
