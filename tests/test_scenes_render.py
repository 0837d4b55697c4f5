"""Every scene we ship loads and renders on PoCL (a smoke test at low resolution and sample count)."""
from pathlib import Path

import numpy as np
import pytest

import clrender

SCENES_DIR = Path(__file__).resolve().parents[1] / "scenes"
SCENES = sorted(SCENES_DIR.rglob("*.xml"))
BIG = {"largemesh_normals.xml", "largemesh_path_mis.xml"}


def _params():
    for p in SCENES:
        marks = [pytest.mark.slow] if p.name in BIG else []
        yield pytest.param(p, id=str(p.relative_to(p.parents[1] if p.parent.name != "scenes" else p.parent)),
                           marks=marks)


@pytest.fixture(scope="module")
def build_module():
    import importlib.util

    spec = importlib.util.spec_from_file_location("scenes_build", SCENES_DIR / "build.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("path", list(_params()))
def test_scene_renders(path, build_module):
    if path.parent.name == "largemesh":  # its PLY meshes are generated on demand, not kept in git
        build_module.ensure_large_meshes(SCENES_DIR)
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
