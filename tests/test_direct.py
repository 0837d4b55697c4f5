"""Direct illumination and path tracing against closed-form values (z-tests on per-pixel estimates).

Every scene here has a single possible bounce (or, for the furnace, a known series), so the direct and the
path integrators must converge to the same analytic value."""
import numpy as np
import pytest

import clrender
from clrender.testing.stats import compare_mean_to_value, compare_to_value
import analytic_scenes as A

ALPHA = 0.01
SPP = 4096


def render(tmp_path, xml, spp=SPP, seed=1):
    p = tmp_path / "scene.xml"
    p.write_text(xml)
    return clrender.render(clrender.load_scene(p), spp=spp, seed=seed)


@pytest.mark.parametrize("integrator", ["direct_ems", "direct_mats", "direct_mis", "whitted",
                                        "path_mats", "path_ems", "path_mis"])
def test_polygon_light_over_a_plane(tmp_path, integrator):
    film = render(tmp_path, A.polygon_light_scene(tmp_path, integrator))
    ref = A.polygon_light_value()
    res = compare_to_value(film, ref, ALPHA)
    assert res.passed, (res.message, film.image[0, 0], ref)


@pytest.mark.parametrize("integrator", ["direct", "direct_ems", "direct_mis", "whitted", "path_ems", "path_mis",
                                        "simple"])
def test_point_light_inverse_square(tmp_path, integrator):
    film = render(tmp_path, A.point_light_scene(tmp_path, integrator), spp=16)
    ref = A.point_light_value(simple=integrator == "simple")
    # A point light's contribution has no variance: the estimate must equal the value to float precision.
    np.testing.assert_allclose(film.image, np.broadcast_to(ref, film.image.shape), rtol=2e-4)


@pytest.mark.parametrize("integrator", ["direct_mats", "path_mats"])
def test_bsdf_sampling_cannot_see_delta_lights(tmp_path, integrator):
    for scene in (A.point_light_scene, A.distant_light_scene):
        film = render(tmp_path, scene(tmp_path, integrator), spp=64)
        assert np.all(film.image == 0.0)


@pytest.mark.parametrize("integrator", ["direct", "direct_ems", "direct_mis", "path_ems", "path_mis"])
def test_distant_light(tmp_path, integrator):
    film = render(tmp_path, A.distant_light_scene(tmp_path, integrator), spp=16)
    np.testing.assert_allclose(film.image, np.broadcast_to(A.distant_light_value(), film.image.shape), rtol=2e-4)


@pytest.mark.parametrize("integrator,expected", [
    ("direct_ems", 1.5), ("direct_mats", 1.5), ("direct_mis", 1.5), ("whitted", 1.5),
    ("path_mats", 2.0), ("path_ems", 2.0), ("path_mis", 2.0),
])
def test_furnace(tmp_path, integrator, expected):
    """Closed box, every wall diffuse rho = 0.5 and emitting Le = 1: direct integrators see Le (1 + rho),
    path integrators the whole series Le / (1 - rho)."""
    film = render(tmp_path, A.furnace_scene(tmp_path, integrator), spp=1024)
    res = compare_mean_to_value(film, expected, ALPHA)
    assert res.passed, (res.message, film.image.mean())


def test_furnace_high_albedo(tmp_path):
    film = render(tmp_path, A.furnace_scene(tmp_path, "path_mis", rho=0.8), spp=2048)
    res = compare_mean_to_value(film, 5.0, ALPHA)
    assert res.passed, (res.message, film.image.mean())
