"""Path tracing: agreement of the three strategies, delta chains with Russian roulette, determinism,
maxDepth, and NaN/Inf samples being dropped and counted."""
import numpy as np
import pytest

import clrender
from clrender import renderer
from clrender.testing.stats import compare_films, compare_mean_to_value
import analytic_scenes as A


def load(tmp_path, xml, name="scene.xml"):
    p = tmp_path / name
    p.write_text(xml)
    return clrender.load_scene(p)


def quad(path, corners, flip=False):
    c = corners[::-1] if flip else corners
    path.write_text("".join(f"v {x:g} {y:g} {z:g}\n" for x, y, z in c) + "f 1 2 3 4\n")


GLOSSY = ('<bsdf type="microfacet"><float name="alpha" value="0.15"/><color name="kd" value="0.2,0.3,0.4"/></bsdf>',
          '<bsdf type="microfacet"><float name="alpha" value="0.5"/><color name="kd" value="0.6,0.3,0.1"/></bsdf>')
SPECULAR = ('<bsdf type="mirror"/>', '<bsdf type="dielectric"/>')


def box_scene(tmp_path, integrator, width=12, height=12, spheres=SPECULAR):
    """A Cornell-like box (open front) with a large ceiling light and two spheres (by default a mirror and a
    glass one)."""
    walls = {
        "floor": [(-1, 0, -1), (1, 0, -1), (1, 0, 1), (-1, 0, 1)],
        "ceil": [(-1, 2, -1), (-1, 2, 1), (1, 2, 1), (1, 2, -1)],
        "back": [(-1, 0, -1), (-1, 2, -1), (1, 2, -1), (1, 0, -1)],
        "left": [(-1, 0, -1), (-1, 0, 1), (-1, 2, 1), (-1, 2, -1)],
        "right": [(1, 0, -1), (1, 2, -1), (1, 2, 1), (1, 0, 1)],
    }
    colors = {"floor": "0.7", "ceil": "0.7", "back": "0.7", "left": "0.6,0.1,0.1", "right": "0.1,0.6,0.1"}
    meshes = []
    for name, c in walls.items():
        c = np.array(c, float)
        n = np.cross(c[1] - c[0], c[2] - c[0])
        inward = n @ (np.array([0, 1, 0]) - c.mean(axis=0)) > 0
        quad(tmp_path / f"{name}.obj", c, flip=not inward)
        meshes.append(f'<mesh type="obj"><string name="filename" value="{name}.obj"/><bsdf type="diffuse">'
                      f'<color name="albedo" value="{colors[name]}"/></bsdf></mesh>')
    # Wound so that its face normal points down, into the box (area lights emit on that side only).
    quad(tmp_path / "light.obj", np.array([(-0.5, 1.98, -0.5), (0.5, 1.98, -0.5), (0.5, 1.98, 0.5),
                                           (-0.5, 1.98, 0.5)], float))
    meshes.append('<mesh type="obj"><string name="filename" value="light.obj"/><emitter type="area">'
                  '<color name="radiance" value="6"/></emitter></mesh>')
    meshes.append('<mesh type="sphere"><point name="center" value="-0.45,0.35,-0.3"/><float name="radius" '
                  f'value="0.35"/>{spheres[0]}</mesh>')
    meshes.append('<mesh type="sphere"><point name="center" value="0.45,0.35,0.3"/><float name="radius" '
                  f'value="0.35"/>{spheres[1]}</mesh>')
    cam = A.camera(width=width, height=height, fov=45, target=(0, 1, 0), origin=(0, 1, 3.4))
    cam = cam.replace('up="0,0,1"', 'up="0,1,0"').replace("<lookat", '<scale value="-1,1,1"/><lookat')
    return load(tmp_path, f'<scene><integrator type="{integrator}"/>{cam}{"".join(meshes)}</scene>')


@pytest.mark.slow
def test_path_strategies_agree_per_pixel(tmp_path):
    films = {k: clrender.render(box_scene(tmp_path, k), spp=8192, seed=i)
             for i, k in enumerate(("path_mats", "path_ems", "path_mis"))}
    for a, b in (("path_mis", "path_mats"), ("path_mis", "path_ems"), ("path_mats", "path_ems")):
        res = compare_films(films[a], films[b], alpha=0.01 / 3)
        assert res.passed, (a, b, res.message)


@pytest.mark.slow
def test_direct_strategies_agree_per_pixel(tmp_path):
    """Without delta BSDFs, direct_ems, direct_mats and direct_mis converge to the same image."""
    films = {k: clrender.render(box_scene(tmp_path, k, spheres=GLOSSY), spp=16384, seed=i)
             for i, k in enumerate(("direct_ems", "direct_mats", "direct_mis"))}
    # A z-test needs the central limit regime: where an estimator found the light in a handful of its samples
    # (BSDF sampling sees a sliver of the light past a sphere in a few pixels: about one hit in 16384 samples,
    # so often none), its sample variance says nothing. (mean / standard error)² estimates the number of
    # contributing samples; compare the pixels where every film has at least 30.
    def well_sampled(f):
        m, se = f.image.astype(np.float64), np.sqrt(f.variance())
        return np.all((m > 0) & (m * m >= 30 * se * se), axis=-1)

    mask = np.logical_and.reduce([well_sampled(f) for f in films.values()])
    assert mask.mean() > 0.8, mask.mean()
    for a, b in (("direct_mis", "direct_ems"), ("direct_mis", "direct_mats"), ("direct_ems", "direct_mats")):
        res = compare_films(films[a], films[b], alpha=0.01 / 3, mask=mask)
        assert res.passed, (a, b, res.message)


def test_direct_strategies_agree_on_the_whole_image(tmp_path):
    from clrender.testing.stats import mean_and_error

    films = [clrender.render(box_scene(tmp_path, k, spheres=GLOSSY), spp=256, seed=i)
             for i, k in enumerate(("direct_ems", "direct_mats", "direct_mis"))]
    (ma, ea), (mb, eb), (mc, ec) = (mean_and_error(f) for f in films)
    for m, e in ((mb, eb), (mc, ec)):
        z = (ma - m) / np.sqrt(ea ** 2 + e ** 2)
        assert np.all(np.abs(z) < 3.5), (ma, m, z)


@pytest.mark.parametrize("integ", ["direct_ems", "direct_mats", "direct_mis", "path_mats", "path_ems", "path_mis",
                                   "whitted"])
def test_back_of_a_one_sided_light_is_black(tmp_path, integ):
    """A camera looking at the back of an area light (whose surface reflects nothing) sees black, with
    every integrator; the front shows the radiance. (One test per integrator: on a GPU run that stalled here,
    the report could not say which one.)"""
    for flip, expected in ((False, 2.5), (True, 0.0)):
        quad(tmp_path / "l.obj", np.array([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], float), flip=flip)
        cam = A.camera(width=2, height=2, fov=10, target=(0, 0, 0), origin=(0, 0, 3)).replace('up="0,0,1"', 'up="0,1,0"')
        scene = load(tmp_path, f'<scene><integrator type="{integ}"/>{cam}<mesh type="obj"><string name="filename" '
                               'value="l.obj"/><bsdf type="diffuse"><color name="albedo" value="0"/></bsdf>'
                               '<emitter type="area"><color name="radiance" value="2.5"/></emitter></mesh></scene>')
        film = clrender.render(scene, spp=4)
        np.testing.assert_allclose(film.image, expected, err_msg=f"{integ}, flipped={flip}")


def test_path_strategies_agree_on_the_whole_image(tmp_path):
    """The quick version: mean over the image (robust to caustic fireflies in single pixels)."""
    mis = clrender.render(box_scene(tmp_path, "path_mis"), spp=512, seed=1)
    for k in ("path_mats", "path_ems"):
        other = clrender.render(box_scene(tmp_path, k), spp=512, seed=2)
        m, _ = __import__("clrender.testing.stats", fromlist=["x"]).mean_and_error(other)
        res = compare_mean_to_value(mis, m, alpha=0.01)
        # Both are noisy: compare with both errors by a two-sample z on the means.
        from clrender.testing.stats import mean_and_error
        ma, ea = mean_and_error(mis)
        mb, eb = mean_and_error(other)
        z = (ma - mb) / np.sqrt(ea ** 2 + eb ** 2)
        assert np.all(np.abs(z) < 3.5), (k, ma, mb, z)


def test_mirror_tube(tmp_path):
    """A square tube of mirrors, a light at the far end: every path from the camera bounces between the
    mirrors until it reaches the light, which it sees with full radiance (mirrors reflect everything), so
    the expected image is the light's radiance wherever the far end is visible -- through up to hundreds of
    delta bounces, with Russian roulette (survival 0.99 per bounce from depth 3) divided out."""
    L = 40.0
    walls = [[(-1, -1, 0), (1, -1, 0), (1, -1, L), (-1, -1, L)], [(-1, 1, 0), (-1, 1, L), (1, 1, L), (1, 1, 0)],
             [(-1, -1, 0), (-1, -1, L), (-1, 1, L), (-1, 1, 0)], [(1, -1, 0), (1, 1, 0), (1, 1, L), (1, -1, L)]]
    meshes = []
    for i, w in enumerate(walls):
        w = np.array(w, float)
        n = np.cross(w[1] - w[0], w[2] - w[0])
        c = w.mean(axis=0)
        quad(tmp_path / f"w{i}.obj", w, flip=n @ (np.array([0, 0, c[2]]) - c) < 0)  # mirrors face inward
        meshes.append(f'<mesh type="obj"><string name="filename" value="w{i}.obj"/><bsdf type="mirror"/></mesh>')
    quad(tmp_path / "end.obj", np.array([(-1, -1, L), (-1, 1, L), (1, 1, L), (1, -1, L)], float))
    meshes.append('<mesh type="obj"><string name="filename" value="end.obj"/><emitter type="area">'
                  '<color name="radiance" value="3,2,1"/></emitter></mesh>')
    cam = A.camera(width=8, height=8, fov=80, target=(0, 0, 10), origin=(0, 0, 0.5)).replace('up="0,0,1"', 'up="0,1,0"')
    for integ in ("path_mats", "path_ems", "path_mis", "whitted"):
        scene = load(tmp_path, f'<scene><integrator type="{integ}"/>{cam}{"".join(meshes)}</scene>')
        film = clrender.render(scene, spp=512, seed=3)
        res = compare_mean_to_value(film, [3, 2, 1], alpha=0.01 / 4)
        assert res.passed, (integ, res.message)


def test_max_depth(tmp_path):
    """maxDepth 1: only emitters seen directly; maxDepth 2: direct illumination (= direct_mis)."""
    xml = A.furnace_scene(tmp_path, "path_mis")
    one = load(tmp_path, xml.replace('<integrator type="path_mis"/>',
                                     '<integrator type="path_mis"><integer name="maxDepth" value="1"/></integrator>'))
    film = clrender.render(one, spp=16)
    np.testing.assert_allclose(film.image, 1.0, rtol=1e-5)
    two = load(tmp_path, xml.replace('<integrator type="path_mis"/>',
                                     '<integrator type="path_mis"><integer name="maxDepth" value="2"/></integrator>'))
    res = compare_mean_to_value(clrender.render(two, spp=1024), 1.5, alpha=0.01)
    assert res.passed, res.message


def test_path_image_independent_of_pass_split(tmp_path, monkeypatch):
    scene = box_scene(tmp_path, "path_mis")
    r = renderer.Renderer(scene)
    monkeypatch.setattr(renderer, "TARGET_LAUNCH_SECONDS", 1e-9)
    a = r.render(spp=5, seed=2)
    monkeypatch.setattr(renderer, "TARGET_LAUNCH_SECONDS", 1e9)
    b = r.render(spp=5, seed=2)
    assert a.stats.passes == 5 and b.stats.passes < 5
    np.testing.assert_allclose(a.sum_wl, b.sum_wl, rtol=1e-5, atol=1e-5)


def test_nan_samples_are_dropped_and_counted(tmp_path):
    """A debug build poisons every 5th sample with NaN and every 7th with Inf: the image stays finite,
    equal to the render of the remaining samples, and the drop count is exact."""
    scene = box_scene(tmp_path, "normals", width=4, height=4)
    poisoned = renderer.Renderer(scene, defines={"CLRENDER_TEST_POISON": 1}).render(spp=35, seed=1)
    n_bad = sum(1 for s in range(35) if s % 5 == 0 or s % 7 == 0)
    assert np.all(np.isfinite(poisoned.image))
    assert poisoned.metadata["dropped_samples"] == n_bad * 16
    assert np.all(poisoned.count == 35 - n_bad)
