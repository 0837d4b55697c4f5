"""The twin scenes of benchmarks/vs_mitsuba.py that are one Mitsuba 3 file read by both renderers: clrender reads
each (load_scene) and renders it at a tiny size; the furnace's analytic regions and image. Mitsuba itself is not
needed (the benchmark compares with it; README "Side by side with Mitsuba 3")."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

import clrender
from clrender.renderer import Renderer

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def vm():
    spec = importlib.util.spec_from_file_location("vs_mitsuba", ROOT / "benchmarks" / "vs_mitsuba.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def write_twin(vm, name, d: Path, spp=1, res=16):
    make = vm.TWINS[name]
    t = vm.twin_large_mesh(d, spp, res, subdivisions=6) if name == "large_mesh" else make(d, spp, res)
    assert "xml" in t, f"{name} is not a one-file twin"
    (d / "scene.xml").write_text(t["xml"])
    return t, d / "scene.xml"


@pytest.mark.parametrize("name, shapes, area_lights, sky", [
    ("rough_plates", 1 + 4 + 4, 4, 1),  # floor, plates, spherical lights; a dim constant sky
    ("large_mesh", 3, 1, 0),
    ("furnace", 1, 0, 1),
    ("cornell_spheres_mi", 5 + 1 + 2, 1, 0),
])
def test_twin_reads_and_renders(vm, tmp_path, name, shapes, area_lights, sky):
    t, xml = write_twin(vm, name, tmp_path)
    scene = clrender.load_scene(xml)
    assert scene.spec.format == "mitsuba"
    assert scene.integrator.spec.type == "path"  # Mitsuba's integrator semantics on both sides
    assert (scene.width, scene.height) == (16, 16)
    assert len(scene.shapes) == shapes and len(scene.emitters) == sky
    assert sum(s.emitter is not None for s in scene.shapes) == area_lights
    img = Renderer(scene).render(spp=1, seed=3).image
    assert img.shape == (16, 16, 3) and np.isfinite(img).all()
    assert img.mean() > 0.01  # lit: the lights and the geometry are where the camera looks


def test_large_mesh_is_a_million_triangles(vm):
    assert 1_000_000 <= 20 * vm.LARGE_MESH_SUBDIVISIONS ** 2 < 1_050_000


def test_large_mesh_ply_is_read_with_its_normals(vm, tmp_path):
    t, xml = write_twin(vm, "large_mesh", tmp_path)
    assert t["triangles"] == 20 * 6 ** 2
    blob = [s for s in clrender.load_scene(xml).shapes if s.spec.type == "ply"]
    assert len(blob) == 1


def test_furnace_masks_split_the_image_at_the_silhouette(vm):
    cam = dict(vm.FURNACE_CAMERA, width=64, height=64)
    m = vm.furnace_masks(cam)
    assert not (m["inside"] & m["outside"]).any()
    # the silhouette's disc, in pixels: inside < disc < everything not outside; the crossed ring is thin
    d = np.linalg.norm(np.subtract(cam["origin"], cam["target"]))
    R = vm.FURNACE_RADIUS / np.sqrt(d * d - vm.FURNACE_RADIUS ** 2)
    disc = np.pi * (R * 64 / (2 * np.tan(np.radians(cam["fov"]) / 2))) ** 2
    assert m["inside"].sum() < disc < 64 * 64 - m["outside"].sum()
    assert 64 * 64 - m["outside"].sum() - m["inside"].sum() < 0.2 * disc
    assert m["inside"][32, 32] and m["outside"][0, 0]


def test_furnace_is_analytic(vm, tmp_path):
    """The sphere's pixels are albedo x sky radiance (a convex object never sees itself), the rest the sky's."""
    t, xml = write_twin(vm, "furnace", tmp_path, res=32)
    img = Renderer(clrender.load_scene(xml)).render(spp=32, seed=5).image.astype(np.float64)
    r = vm.furnace_report(img, t["analytic"])
    assert r["outside"]["mean"] == pytest.approx(1.0, abs=1e-6)
    inside = r["inside"]
    assert inside["pixels"] > 200
    assert abs(inside["mean"] - vm.FURNACE_ALBEDO) < 4 * inside["stderr"] + 1e-4, inside
