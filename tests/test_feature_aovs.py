"""Feature AOVs (kernels/feature_aovs.h, Film.aov): albedo and normal of the first non-specular surface, depth and
position of the first hit, in both executors, and `--aov` on the command line.

- A diffuse plane of one colour: the albedo is that colour (one cosine-weighted BSDF sample's weight is exact).
- An analytic sphere filling the view: a sphere's normal is (p - c) / r, linear in p, so each pixel's mean normal is
  (mean position - c) / r exactly, and every mean position lies on the sphere up to the curvature within a pixel.
- Through a perfect mirror: the albedo and normal are those of the diffuse ceiling the mirror shows, the depth and
  position those of the mirror.
- Without --aov the program is the one it always was (no CLR_FEATURE_AOVS define).
- Every integrator's kernel writes the same features (they describe the camera's first hits, not the integrator's
  light transport): the diffuse plane's albedo, normal and position under each.
"""
import numpy as np
import pytest

import clrender
from clrender.film import read_exr
from clrender.renderer import Renderer

from clrender.scene.registry import _REGISTRY, instantiate

from analytic_scenes import RHO, X0, camera, plane_mesh, point_light_scene

CENTRE, RADIUS = np.array([0.3, -0.2, 0.1]), 0.7


def load(tmp_path, body, width=2, height=2, cam=None):
    xml = tmp_path / "s.xml"
    xml.write_text(f'<scene><integrator type="path_mis"/>{cam or camera(width, height)}{body}</scene>')
    return clrender.load_scene(xml)


@pytest.mark.parametrize("driver", ["megakernel", "wavefront"])
def test_albedo_of_a_diffuse_colour(tmp_path, driver):
    scene = load(tmp_path, plane_mesh(tmp_path / "plane.obj"))
    film = Renderer(scene, feature_aovs=True, driver=driver).render(spp=8, seed=3)
    np.testing.assert_allclose(film.aov("albedo"), np.broadcast_to(RHO, (2, 2, 3)), rtol=1e-5)
    np.testing.assert_allclose(film.aov("normal"), np.broadcast_to([0, 0, 1], (2, 2, 3)), atol=1e-6)
    np.testing.assert_allclose(film.aov("position"), np.broadcast_to(X0, (2, 2, 3)), atol=2e-3)


def test_normal_of_a_sphere(tmp_path):
    c = ",".join(map(str, CENTRE))
    origin = CENTRE + np.array([2.0, 0.5, 1.0])
    cam = camera(16, 16, fov=8.0, target=CENTRE, origin=origin)   # the sphere fills the view
    body = (f'<mesh type="sphere"><point name="center" value="{c}"/><float name="radius" value="{RADIUS}"/>'
            f'<bsdf type="diffuse"/></mesh>')
    film = Renderer(load(tmp_path, body, cam=cam), feature_aovs=True).render(spp=4, seed=1)
    pos, nrm, depth = film.aov("position"), film.aov("normal"), film.aov("depth")
    assert np.all(depth > 0)
    np.testing.assert_allclose(nrm, (pos - CENTRE) / RADIUS, atol=2e-5)
    np.testing.assert_allclose(np.linalg.norm(pos - CENTRE, axis=-1), RADIUS, rtol=2e-3)
    # the depth of each pixel against its position: the distance from the pinhole less the near clip distance
    dist = np.linalg.norm(pos - origin, axis=-1)
    offset = dist - depth
    assert np.ptp(offset) < 2e-3 * dist.max()


def test_through_a_mirror(tmp_path):
    (tmp_path / "mirror.obj").write_text("v -50 -50 0\nv 50 -50 0\nv 50 50 0\nv -50 50 0\nf 1 2 3 4\n")
    (tmp_path / "ceiling.obj").write_text("v -50 -50 3\nv -50 50 3\nv 50 50 3\nv 50 -50 3\nf 1 2 3 4\n")
    rho = ",".join(map(str, RHO))
    body = ('<mesh type="obj"><string name="filename" value="mirror.obj"/><bsdf type="mirror"/></mesh>'
            f'<mesh type="obj"><string name="filename" value="ceiling.obj"/><bsdf type="diffuse">'
            f'<color name="albedo" value="{rho}"/></bsdf></mesh>')
    film = Renderer(load(tmp_path, body), feature_aovs=True).render(spp=8, seed=2)
    np.testing.assert_allclose(film.aov("albedo"), np.broadcast_to(RHO, (2, 2, 3)), rtol=1e-5)
    np.testing.assert_allclose(film.aov("normal"), np.broadcast_to([0, 0, -1], (2, 2, 3)), atol=1e-6)
    np.testing.assert_allclose(film.aov("position"), np.broadcast_to(X0, (2, 2, 3)), atol=2e-3)   # the mirror's


#: the properties an integrator requires (simple's come with analytic_scenes.point_light_scene)
REQUIRED = {"av": {"length": ("float", 1.0)}, "aov": {"aovs": ("string", "dd.y:depth")}}
#: integrators whose kernels include kernels/integrators/lighting.h themselves, as path_mis does (the default run's
#: tests above): feature_aovs.h compiled with them before it included lighting.h too, so they only guard against a
#: change to that header and run with the long suites
LIGHTING_KERNELS = {"path_mis", "aov", "direct", "direct_ems", "direct_mats", "direct_mis", "material", "path_ems", "path_mats",
                    "whitted", "direct_mitsuba", "path_mitsuba"}


def _kernels():
    """(format, type) of one integrator per kernel of kernels/integrators/ (moment renders the one it holds)."""
    seen = {}
    for (fmt, tag, name), cls in sorted(_REGISTRY.items()):
        kernel = getattr(cls, "kernel", None)
        if tag == "integrator" and kernel and kernel not in seen:
            seen[kernel] = (fmt, name)
    for kernel, (fmt, name) in sorted(seen.items()):
        marks = pytest.mark.slow if kernel in LIGHTING_KERNELS else ()
        yield pytest.param(fmt, name, id=kernel, marks=marks)


@pytest.mark.parametrize("fmt,name", list(_kernels()))
def test_every_integrator_writes_them(tmp_path, fmt, name):
    """ao, av, normals and simple include no lighting.h of their own, and the features did not compile with them."""
    xml = tmp_path / "s.xml"
    xml.write_text(point_light_scene(tmp_path, "simple" if name == "simple" else "path_mis"))
    scene = clrender.load_scene(xml)
    if name != "simple":
        scene.integrator = instantiate("integrator", name, REQUIRED.get(name, {}), fmt=fmt)
    film = Renderer(scene, feature_aovs=True).render(spp=4, seed=5)
    np.testing.assert_allclose(film.aov("albedo"), np.broadcast_to(RHO, (2, 2, 3)), rtol=1e-5)
    np.testing.assert_allclose(film.aov("normal"), np.broadcast_to([0, 0, 1], (2, 2, 3)), atol=1e-6)
    np.testing.assert_allclose(film.aov("position"), np.broadcast_to(X0, (2, 2, 3)), atol=2e-3)
    assert np.all(film.aov("depth") > 0)


def test_without_features_the_program_is_unchanged(tmp_path):
    scene = load(tmp_path, plane_mesh(tmp_path / "plane.obj"))
    r = Renderer(scene)
    assert "CLR_FEATURE_AOVS" not in r.defines
    film = r.render(spp=2)
    with pytest.raises(ValueError, match="feature_aovs=True"):
        film.aov("albedo")
    with pytest.raises(ValueError, match="unknown AOV"):
        film.aov("albedos")


def test_command_line(tmp_path, capsys):
    import OpenEXR

    from clrender.cli import main

    (tmp_path / "s.xml").write_text(f'<scene><integrator type="path_mis"/>{camera(2, 2)}'
                                    f'{plane_mesh(tmp_path / "plane.obj")}</scene>')
    out = tmp_path / "o.exr"
    assert main(["render", str(tmp_path / "s.xml"), "-o", str(out), "-q", "--spp", "4",
                 "--aov", "albedo,normal,depth,position,variance,count"]) == 0
    with OpenEXR.File(str(out)) as f:
        ch = f.channels()
        np.testing.assert_allclose(np.asarray(ch["albedo"].pixels), np.broadcast_to(RHO, (2, 2, 3)), rtol=1e-5)
        assert np.all(np.asarray(ch["count"].pixels) == 4)
        assert {"normal", "depth", "position", "variance"} <= set(ch)
    img, _ = read_exr(out)
    assert img.shape == (2, 2, 3)
    assert main(["render", str(tmp_path / "s.xml"), "-o", str(out), "-q", "--aov", "albedo,nope"]) == 2
    assert "unknown layer 'nope'" in capsys.readouterr().err


def test_parts_and_merge_carry_them(tmp_path):
    """Two --sample-range parts with --aov merge into the layers of the single render of their union."""
    import OpenEXR

    from clrender.cli import main

    (tmp_path / "s.xml").write_text(f'<scene><integrator type="path_mis"/>{camera(2, 2)}'
                                    f'{plane_mesh(tmp_path / "plane.obj")}</scene>')
    common = ["-q", "--seed", "3", "--aov", "albedo,normal,count"]
    for i, rng in enumerate(("0:3", "3:5")):
        assert main(["render", str(tmp_path / "s.xml"), "--sample-range", rng, "-o", str(tmp_path / f"p{i}.exr"),
                     *common]) == 0
    assert main(["merge", str(tmp_path / "p0.exr"), str(tmp_path / "p1.exr"), "-o", str(tmp_path / "m.exr")]) == 0
    assert main(["render", str(tmp_path / "s.xml"), "--spp", "8", "-o", str(tmp_path / "w.exr"), *common]) == 0
    with OpenEXR.File(str(tmp_path / "m.exr")) as m, OpenEXR.File(str(tmp_path / "w.exr")) as w:
        for name in ("albedo", "normal", "count"):
            np.testing.assert_allclose(np.asarray(m.channels()[name].pixels), np.asarray(w.channels()[name].pixels),
                                       rtol=1e-5, atol=1e-7)
    # a part without the layers does not belong with one that has them
    assert main(["render", str(tmp_path / "s.xml"), "--sample-range", "5:1", "-o", str(tmp_path / "p2.exr"),
                 "-q", "--seed", "3"]) == 0
    assert main(["merge", str(tmp_path / "p0.exr"), str(tmp_path / "p1.exr"), str(tmp_path / "p2.exr"), "-o",
                 str(tmp_path / "m2.exr")]) == 2
