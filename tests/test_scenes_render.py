"""Every scene we ship loads and renders on PoCL (a smoke test at low resolution and sample count)."""
from pathlib import Path

import numpy as np
import pytest

import clrender

SCENES = sorted((Path(__file__).resolve().parents[1] / "scenes").rglob("*.xml"))
BIG = {"largemesh_normals.xml", "largemesh_path_mis.xml"}


def _params():
    for p in SCENES:
        marks = [pytest.mark.slow] if p.name in BIG else []
        yield pytest.param(p, id=str(p.relative_to(p.parents[1] if p.parent.name != "scenes" else p.parent)),
                           marks=marks)


@pytest.mark.parametrize("path", list(_params()))
def test_scene_renders(path):
    scene = clrender.load_scene(path)
    cam = scene.camera
    scale = 32 / max(cam.width, cam.height)
    cam.width, cam.height = max(1, round(cam.width * scale)), max(1, round(cam.height * scale))
    film = clrender.render(scene, spp=2, seed=0)
    img = film.image
    assert img.shape == (cam.height, cam.width, 3)
    assert np.all(np.isfinite(img))
    assert img.max() > 0, "a shipped scene should not render black"
    assert film.metadata["dropped_samples"] == 0
