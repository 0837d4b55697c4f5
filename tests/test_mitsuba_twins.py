"""Mitsuba twin scenes: each tests/mitsuba/scenes/<name>.xml is read unchanged by Mitsuba 3 (which rendered
tests/mitsuba/refs/<name>.npz with tests/mitsuba/make_refs.py) and by clrender, which must agree with the
reference pixel by pixel: a z-test of the difference against both standard errors combined, Šidák-corrected
over every pixel and channel (clrender/testing/stats.py; clrender's variance is floored by what Mitsuba's
per-sample variance implies at clrender's sample count, so a pixel whose rare paths clrender missed does not fail on
noise, and for wide filters by the spread of Mitsuba's image over the filter's footprint). Mitsuba is not needed
to run this."""
import sys
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent / "mitsuba"
sys.path.insert(0, str(HERE))
from make_volumes import write_volumes  # noqa: E402

SCENES = sorted(p.stem for p in (HERE / "scenes").glob("*.xml") if (HERE / "refs" / f"{p.stem}.npz").is_file())


@pytest.fixture(autouse=True, scope="module")
def volume_grids():
    """The grids scenes/volumes/*.vol that media twins read, written from deterministic functions (not committed)."""
    write_volumes()


def render_twin(name: str, seed: int = 7, **defines):
    import clrender

    scene = clrender.load_scene(HERE / "scenes" / f"{name}.xml", **defines)
    return scene, clrender.render(scene, seed=seed)


def reference(name: str):
    """(mean, stderr, samples per pixel) of Mitsuba's render."""
    with np.load(HERE / "refs" / f"{name}.npz") as z:
        return z["mean"], z["stderr"], int(z["spp"])


def test_every_twin_has_a_reference():
    missing = [p.stem for p in (HERE / "scenes").glob("*.xml") if not (HERE / "refs" / f"{p.stem}.npz").is_file()]
    assert not missing, f"run tests/mitsuba/make_refs.py {' '.join(missing)}"


@pytest.mark.slow
@pytest.mark.parametrize("name", SCENES)
def test_twin_matches_mitsuba(name):
    from clrender.testing.stats import compare_image_means, compare_to_reference

    mean, stderr, ref_spp = reference(name)
    scene, film = render_twin(name)
    assert film.image.shape == mean.shape, f"clrender renders {film.image.shape}, Mitsuba {mean.shape}"
    result = compare_to_reference(film, mean, stderr, ref_samples=ref_spp, rfilter=scene.camera.filter)
    means = f"means: clrender {film.image.mean(axis=(0, 1)).round(4)}, Mitsuba {mean.mean(axis=(0, 1)).round(4)}"
    assert result.passed, f"{name}: {result.message}; {means}"
    # A small bias spread over the whole image hides in the per-pixel noise; the image mean shows it.
    overall = compare_image_means(film, mean, stderr, ref_spp, rfilter=scene.camera.filter)
    assert overall.passed, f"{name}: {overall.message}"


def _mirror(scene):
    scene.camera.mirror_x = False          # Nori's eth convention (+x on the image's right), not Mitsuba's


def _crop_off_by_one(scene):
    scene.camera.film.crop_x += 1


def _pinhole(scene):
    scene.camera.lens_radius = 0.0


def _border_ignored(scene):
    scene.camera.film.sample_border = False


def _fov_one_percent_wider(scene):
    scene.camera.fov *= 1.01


def _path_rules(scene):
    scene.integrator.volpath = False       # Mitsuba's path: null events count, hide_emitters sees through


def _principled_glass_eta(scene):
    glass = [s.bsdf for s in scene.shapes if type(s.bsdf).__name__ == "Principled" and s.bsdf.has_spec_trans]
    assert glass
    for b in glass:
        b.eta = 1.33


def _projector_square_image(scene):
    for e in scene.emitters:
        if type(e).__name__ == "ProjectorEmitter":
            e.v_scale = e.u_scale          # the aspect ratio of the projected image's resolution ignored


def _smoke_denser(scene):
    smoke = next(s.interior for s in scene.shapes if s.interior is not None)
    smoke.scale *= 1.1                     # sigma_t 10% denser (the majorant with it)
    smoke.majorant *= 1.1


def _sdf_normals_analytic(scene):
    from clrender.shapes.instance import Instance
    from clrender.shapes.sdfgrid import SDFGrid

    grids = [g for s in scene.shapes for g in (s.group.shapes if isinstance(s, Instance) else [s])
             if isinstance(g, SDFGrid) and g.smooth]
    assert grids
    for g in grids:
        g.smooth = False                   # the geometric normal shades: Mitsuba's `analytic`, not its default


@pytest.mark.slow
@pytest.mark.parametrize("name, mutate", [
    ("cornell_meshes", _mirror), ("filter_lanczos_crop", _crop_off_by_one), ("thinlens", _pinhole),
    ("gaussian_sample_border", _border_ignored), ("filter_gaussian_fov_y", _fov_one_percent_wider),
    ("integrator_volpath_depth2", _path_rules), ("integrator_volpath_hide", _path_rules),
    ("orthographic", _mirror), ("principled", _principled_glass_eta), ("projector", _projector_square_image),
    ("media_smoke", _smoke_denser), ("sdfgrid", _sdf_normals_analytic), ("sdfgrid_normals", _sdf_normals_analytic),
], ids=["mirrored camera", "crop window 1 px off", "pinhole for thin lens", "sample_border ignored", "fov 1% wider",
        "volpath depth as path's", "volpath hide_emitters as path's", "mirrored orthographic sensor",
        "principled glass eta 1.33 for 1.5", "projector's image taken as square", "smoke 10% denser",
        "SDF grid shaded by its analytic normals", "SDF grid's analytic normals for smooth"])
def test_twin_test_fails_when_clrender_is_wrong(name, mutate):
    """The harness can fail: each twin, rendered with one thing it verifies done wrong, must not pass."""
    import clrender
    from clrender.testing.stats import compare_image_means, compare_to_reference

    mean, stderr, ref_spp = reference(name)
    scene = clrender.load_scene(HERE / "scenes" / f"{name}.xml")
    mutate(scene)
    film = clrender.render(scene, seed=7)
    result = compare_to_reference(film, mean, stderr, ref_samples=ref_spp, rfilter=scene.camera.filter)
    overall = compare_image_means(film, mean, stderr, ref_spp, rfilter=scene.camera.filter)
    assert not (result.passed and overall.passed), f"{result.message}; {overall.message}"
