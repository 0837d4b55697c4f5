"""Generate the textures of the normalmap/bumpmap twin scenes (tests/mitsuba/scenes/normalmap.xml, bumpmap.xml):

    python tests/mitsuba/make_perturbed_assets.py

- textures/dimples_height.png: a 64 x 64 8-bit grey height field: a 4 x 4 grid of round dimples and bumps (a smooth
  bump profile, alternating in sign) on a gentle diagonal ripple, 0.5 at rest;
- textures/dimples_normal.png: the tangent-space normal map of the same field, (n + 1) / 2 per channel, with
  n = normalize(-k dh/du, -k dh/dv, 1) (k = 0.12: tilts up to about 50 degrees).

Both are meant to be read raw (their values are heights and vectors, not colours). Made here from formulas
(deterministic); the files are committed and kept small.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent / "scenes"
sys.path.insert(0, str(HERE.parents[2]))
from clrender.png import encode_png  # noqa: E402


def height(u, v):
    """The height field over uv in [0, 1)^2 (periodic), values within [0, 1]."""
    cu, cv = (np.floor(u * 4) + 0.5) / 4, (np.floor(v * 4) + 0.5) / 4
    r = np.hypot(u - cu, v - cv) / 0.11
    sign = np.where((np.floor(u * 4) + np.floor(v * 4)) % 2 == 0, 1.0, -1.0)
    bump = np.where(r < 1, (1 - r * r) ** 2, 0.0)
    return 0.5 + 0.35 * sign * bump + 0.08 * np.sin(2 * np.pi * (u + 2 * v))


def main():
    n = 64
    u = (np.arange(n) + 0.5) / n
    uu, vv = np.meshgrid(u, u)                       # row j is v = (j + 0.5) / n: Mitsuba's first row is v = 0
    h = height(uu, vv)
    grey = np.round(np.clip(h, 0, 1) * 255).astype(np.uint8)
    (HERE / "textures" / "dimples_height.png").write_bytes(encode_png(np.repeat(grey[..., None], 3, -1)))
    eps = 1e-4
    dhdu = (height(uu + eps, vv) - height(uu - eps, vv)) / (2 * eps)
    dhdv = (height(uu, vv + eps) - height(uu, vv - eps)) / (2 * eps)
    k = 0.12
    nrm = np.stack([-k * dhdu, -k * dhdv, np.ones_like(h)], -1)
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    (HERE / "textures" / "dimples_normal.png").write_bytes(encode_png(np.round((nrm + 1) / 2 * 255).astype(np.uint8)))
    print("wrote textures/dimples_height.png, textures/dimples_normal.png")


if __name__ == "__main__":
    main()
