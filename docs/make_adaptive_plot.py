"""docs/adaptive_counts.png: where adaptive sampling puts its samples. Our Veach MIS scene, rendered adaptively
(target error 0.1, 16 to 512 spp), beside its count layer (log scale, dark = few samples, bright = many).

    python docs/make_adaptive_plot.py [--res 256]
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def heat(x: np.ndarray) -> np.ndarray:
    """(H, W) in [0, 1] to RGB uint8 along black, blue, magenta, orange, yellow."""
    stops = np.array([[0, 0, 0], [40, 40, 160], [180, 40, 140], [250, 140, 30], [255, 250, 120]], float)
    t = np.clip(x, 0, 1) * (len(stops) - 1)
    i = np.minimum(t.astype(int), len(stops) - 2)
    f = (t - i)[..., None]
    return (stops[i] * (1 - f) + stops[i + 1] * f).astype(np.uint8)


def main():
    from PIL import Image, ImageDraw

    import clrender
    from clrender.film import to_srgb8
    from clrender.renderer import Renderer

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--res", type=int, default=256)
    a = ap.parse_args()
    scene = clrender.load_scene(ROOT / "scenes" / "mis" / "mis_path_mis.xml")
    w, h = scene.width, scene.height
    scene.camera.width, scene.camera.height = a.res * w // max(w, h), a.res * h // max(w, h)
    # uniform_below=0: the plot shows where the stopping rule sends samples; left to itself, a render of this scene
    # finishes as a uniform one (its noise is too even to gain: clrender/adaptive.py)
    film = Renderer(scene).render_adaptive(target_error=0.1, min_spp=16, max_spp=512, seed=1, uniform_below=0)
    c = film.count
    lo, hi = np.log2(16), np.log2(512)
    left = Image.fromarray(to_srgb8(film.image))
    right = Image.fromarray(heat((np.log2(np.maximum(c, 1)) - lo) / (hi - lo)))
    W, H = left.size
    out = Image.new("RGB", (2 * W + 10, H + 22), "white")
    out.paste(left, (0, 0))
    out.paste(right, (W + 10, 0))
    ImageDraw.Draw(out).text((4, H + 4), f"adaptive, E = 0.1: {c.mean():.0f} spp on average, {c.min():.0f} to "
                                         f"{c.max():.0f} (right: samples per pixel, log scale 16..512)", fill="black")
    path = ROOT / "docs" / "adaptive_counts.png"
    out.save(path)
    print(f"wrote {path}: mean {c.mean():.1f} spp, {film.stats.seconds:.1f} s")


if __name__ == "__main__":
    main()
