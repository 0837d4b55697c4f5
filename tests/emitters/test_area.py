"""Nori's area emitter (clrender/emitters/area.py, kernels/emitters/area.h) on meshes and analytic spheres, on the
device: chi-square of its sampled directions against its own pdf (triangles of very unequal areas, a closed smooth
mesh seen from outside, overlapping sheets, a sphere from outside and inside), weight == eval / pdf per sample,
shadow rays that do not hit the light itself, one-sidedness by the shading normal, a check that the chi-square
rejects the pdf without the light's cosine, and a polygon light's render against Lambert's formula. (Set-up:
emitter_common.py.)"""
import numpy as np
import pytest

import analytic_scenes as A
import clrender
from clrender.testing.stats import compare_to_value

from .emitter_common import CHI2_CASES, _refs, check_chi2_case, check_weight_case, run_chi2


@pytest.mark.plugin("area", "sampling")
@pytest.mark.parametrize("case", ["area-unequal-triangles", "area-closed-smooth-mesh", "area-overlapping-sheets",
                                  "sphere-outside", "sphere-inside"])
def test_chi2_emitter_sampling(scenes, case):
    check_chi2_case(scenes, case)


def test_chi2_rejects_area_pdf_without_light_cosine(scenes):
    """dist²/A instead of dist²/(A |cos θ_l|): the chi-square code must reject it."""
    stem, e, ref, _, n, sub = CHI2_CASES["area-unequal-triangles"]
    r = run_chi2(scenes[stem], e, ref, 2, n, sub, seed=99)
    assert not r.passed, r.message
    stem, e, ref, _, n, sub = CHI2_CASES["area-closed-smooth-mesh"]
    r = run_chi2(scenes[stem], e, ref, 2, n, sub, seed=98)
    assert not r.passed, r.message


@pytest.mark.parametrize("case", ["unequal", "closed", "ceiling", "sphere", "far_sphere"])
def test_weight_is_eval_over_pdf(scenes, case):
    check_weight_case(scenes, case)


def test_shadow_ray_length_does_not_self_occlude(scenes):
    """scene_occluded(ref, wi, eps, dist (1 - 1e-4)) must not hit the light itself (the area lights, and beside them
    the sun and sky of test_distantdisk.py and test_constant.py)."""
    rng = np.random.default_rng(3)
    n = 20_000
    for stem in ("ceiling", "far_sphere", "sun"):
        refs = _refs(rng, n, [-1.0, 0.01, -1.0], [1.0, 1.5, 1.0])
        for e in range(len(scenes[stem].b.emitters)):
            s = scenes[stem].sample(e, refs, rng.random((n, 2), dtype=np.float32))
            front = np.any(s["w"] > 0, axis=1)
            assert front.mean() > 0.4, stem
            # the sun/sky scene has a ground plane: only directions above it are free
            free = front & (s["wi"][:, 1] > 0)
            assert s["occluded"][free].sum() == 0, f"{stem}: {int(s['occluded'][free].sum())} self-occluded"


def test_area_light_is_one_sided_by_shading_normal(scenes):
    """The ceiling light's vn point down (-y); its winding normal points up. Below it: radiance; above: none."""
    d = scenes["ceiling"]
    row = d.b.emitters[0]
    L = row["area"]["radiance"][:3]
    below = d.hit_le([0.3, 1.0, 0.1], np.array([[0, 1, 0], [0.1, 1, 0.05]], np.float32))
    above = d.hit_le([0.3, 3.0, 0.1], np.array([[0, -1, 0], [0.1, -1, 0.05]], np.float32))
    assert np.all(below[:, 3] == 1) and np.all(above[:, 3] == 1)
    np.testing.assert_allclose(below[:, :3], [L, L])
    np.testing.assert_allclose(above[:, :3], 0)
    s = d.sample(0, [0.3, 3.0, 0.1], np.random.default_rng(1).random((256, 2), dtype=np.float32))
    assert np.all(s["w"] == 0) and np.all(s["pdf"] > 0)
    # total area, packed with the emitting shape
    assert d.b.shapes[row["shape"]]["area"] == pytest.approx(0.8, rel=1e-6)


@pytest.mark.plugin("area", "render")
def test_polygon_light_over_a_plane(tmp_path):
    """A quad light over a diffuse plane (path_mis, 4096 spp): Lambert's polygon irradiance (tests/analytic_scenes.py),
    per pixel."""
    p = tmp_path / "scene.xml"
    p.write_text(A.polygon_light_scene(tmp_path, "path_mis"))
    film = clrender.render(clrender.load_scene(p), spp=4096, seed=1)
    res = compare_to_value(film, A.polygon_light_value(), 0.01)
    assert res.passed, (res.message, film.image[0, 0])
