"""Mitsuba 3's integrators `path` (and `volpath`, `prb`), `direct` and `aov` (clrender/integrators/path.py, direct.py,
aov.py) on scenes with closed-form images: the furnace's geometric series per max_depth, max_depth 1 and 2 as emitter-only and direct
illumination, Russian roulette leaving the mean alone, hide_emitters, the direct integrator's sample counts, and the
AOVs. The scenes are Nori files (tests/analytic_scenes.py) whose integrator is replaced by a Mitsuba-format one, as
a Mitsuba file would make it (registry.instantiate(..., fmt="mitsuba")). Agreement with Mitsuba's own renders is
tests/test_mitsuba_twins.py's job."""
import numpy as np
import pytest

import clrender
import clrender.plugins  # noqa: F401  (registers the plugins: a test run alone must not depend on others)
from clrender.errors import SceneError
from clrender.scene.registry import instantiate
from clrender.testing.stats import _ztest, compare_mean_to_value, compare_to_value, mean_and_error
import analytic_scenes as A

ALPHA = 0.01
TAGS = {bool: "boolean", int: "integer", str: "string", float: "float"}


def mitsuba_integrator(type_name, **props):
    return instantiate("integrator", type_name, {k: (TAGS[type(v)], v) for k, v in props.items()},
                       fmt="mitsuba")


def load(tmp_path, xml, type_name, **props):
    p = tmp_path / "scene.xml"
    p.write_text(xml)
    scene = clrender.load_scene(p)
    scene.integrator = mitsuba_integrator(type_name, **props)
    return scene


def render(tmp_path, xml, type_name, spp, seed=1, **props):
    return clrender.render(load(tmp_path, xml, type_name, **props), spp=spp, seed=seed)


def two_sample_z(a, b):
    (ma, ea), (mb, eb) = mean_and_error(a), mean_and_error(b)
    return (ma - mb) / np.sqrt(ea ** 2 + eb ** 2)


# --- path: max_depth and Russian roulette ------------------------------------------------------------------------

@pytest.mark.parametrize("max_depth", [1, 2, 3, 4, 7, -1])
def test_furnace_series_per_max_depth(tmp_path, max_depth):
    """Closed box, walls diffuse rho = 0.5 emitting Le = 1: a path of at most d segments gathers
    Le (1 + rho + ... + rho^(d-1)); no limit gives Le / (1 - rho) = 2."""
    rho = 0.5
    expected = 1 / (1 - rho) if max_depth == -1 else sum(rho ** k for k in range(max_depth))
    film = render(tmp_path, A.furnace_scene(tmp_path, "path_mis", rho=rho), "path", spp=1024, max_depth=max_depth)
    if max_depth == 1:   # emitters seen directly, nothing sampled: exact
        np.testing.assert_allclose(film.image, 1.0, rtol=1e-6)
        return
    res = compare_mean_to_value(film, expected, ALPHA)
    assert res.passed, (max_depth, res.message, film.image.mean(), expected)


def test_max_depth_zero_renders_nothing(tmp_path):
    film = render(tmp_path, A.furnace_scene(tmp_path, "path_mis"), "path", spp=4, max_depth=0)
    assert np.all(film.image == 0.0)


@pytest.mark.parametrize("rr_depth", [1, 50])
def test_russian_roulette_keeps_the_mean(tmp_path, rr_depth):
    """rho = 0.8: the series is 5; roulette from the first bounce (rr_depth 1) or practically never (50)
    changes the noise, not the mean."""
    film = render(tmp_path, A.furnace_scene(tmp_path, "path_mis", rho=0.8), "path", spp=2048, rr_depth=rr_depth)
    res = compare_mean_to_value(film, 5.0, ALPHA)
    assert res.passed, (rr_depth, res.message, film.image.mean())


def test_russian_roulette_depth_changes_the_noise(tmp_path):
    """The check above can only fail if rr_depth reaches the kernel: roulette from depth 1 must be noisier."""
    xml = A.furnace_scene(tmp_path, "path_mis", rho=0.8)
    early = render(tmp_path, xml, "path", spp=1024, rr_depth=1)
    late = render(tmp_path, xml, "path", spp=1024, rr_depth=50)
    assert early.variance().mean() > 1.5 * late.variance().mean()


def test_max_depth_one_shows_emitters_only(tmp_path):
    """A plane lit by a quad light: with max_depth 1 the plane is black, the light (seen head on) its radiance."""
    film = render(tmp_path, A.polygon_light_scene(tmp_path, "path_mis"), "path", spp=16, max_depth=1)
    assert np.all(film.image == 0.0)
    up = light_over_plane_from_below(tmp_path)
    film = render(tmp_path, up, "path", spp=16, max_depth=1)
    np.testing.assert_allclose(film.image, np.broadcast_to(A.LE, film.image.shape), rtol=1e-6)


@pytest.mark.parametrize("max_depth", [2, -1])
def test_path_direct_illumination_is_analytic(tmp_path, max_depth):
    """The light's BSDF is black, so every path has one bounce: max_depth 2 and no limit both give
    rho/pi Le E (polygon irradiance)."""
    film = render(tmp_path, A.polygon_light_scene(tmp_path, "path_mis"), "path", spp=4096, max_depth=max_depth)
    res = compare_to_value(film, A.polygon_light_value(), ALPHA)
    assert res.passed, (res.message, film.image[0, 0], A.polygon_light_value())


def test_path_with_max_depth_two_equals_direct(tmp_path):
    """On the glossy box (indirect light everywhere), path with max_depth 2 and direct render the same image:
    a two-sample z-test on the image means, and on a third strategy (Nori's direct_mis)."""
    from test_path import GLOSSY, box_scene

    scene = box_scene(tmp_path, "direct_mis", spheres=GLOSSY)
    nori = clrender.render(scene, spp=256, seed=3)
    scene.integrator = mitsuba_integrator("path", max_depth=2)
    path2 = clrender.render(scene, spp=256, seed=1)
    scene.integrator = mitsuba_integrator("direct")
    direct = clrender.render(scene, spp=256, seed=2)
    for other in (direct, nori):
        z = two_sample_z(path2, other)
        assert np.all(np.abs(z) < 3.5), z
    scene.integrator = mitsuba_integrator("path", max_depth=3)
    three = clrender.render(scene, spp=256, seed=4)
    assert np.all(two_sample_z(three, path2) > 5), "one more bounce must add light (the test can fail)"


def test_path_through_delta_bsdfs_agrees_with_nori_path(tmp_path):
    """The box with a mirror and a glass sphere (delta BSDFs, caustics): Mitsuba's path and Nori's path_mis
    converge to the same image mean."""
    from test_path import box_scene

    scene = box_scene(tmp_path, "path_mis")
    nori = clrender.render(scene, spp=512, seed=1)
    scene.integrator = mitsuba_integrator("path")
    mi = clrender.render(scene, spp=512, seed=2)
    z = two_sample_z(mi, nori)
    assert np.all(np.abs(z) < 3.5), z


def test_point_and_distant_lights(tmp_path):
    """Delta lights are found by emitter sampling alone, exactly (no variance)."""
    for make, value in ((A.point_light_scene, A.point_light_value()), (A.distant_light_scene, A.distant_light_value())):
        for type_name in ("path", "direct"):
            film = render(tmp_path, make(tmp_path, "path_mis"), type_name, spp=16)
            np.testing.assert_allclose(film.image, np.broadcast_to(value, film.image.shape), rtol=2e-4,
                                       err_msg=f"{make.__name__} {type_name}")


# --- hide_emitters -----------------------------------------------------------------------------------------------

def light_over_plane_from_below(tmp_path):
    """The quad light seen from below, head on (camera under the light, looking up at its emitting side)."""
    xml = A.polygon_light_scene(tmp_path, "path_mis")
    c = A.QUAD_LIGHT.mean(axis=0)
    cam = A.camera(target=tuple(c), origin=(c[0], c[1], 0.5)).replace('up="0,0,1"', 'up="0,1,0"')
    start = xml.index("<camera")
    return xml[:start] + cam + xml[xml.index("</camera>") + len("</camera>"):]


def looking_down_through_the_light(tmp_path):
    """The camera above the light, looking straight down through it at X0 on the plane: it sees the light's back
    (black: its BSDF reflects nothing and it emits downwards only)."""
    xml = A.polygon_light_scene(tmp_path, "path_mis")
    cam = A.camera(target=tuple(A.X0), origin=(A.X0[0], A.X0[1], 3.0)).replace('up="0,0,1"', 'up="0,1,0"')
    start = xml.index("<camera")
    return xml[:start] + cam + xml[xml.index("</camera>") + len("</camera>"):]


@pytest.mark.parametrize("type_name", ["path", "direct"])
def test_hide_emitters_sees_through_emitters(tmp_path, type_name):
    """As Mitsuba 3.9 renders hide_emitters: the camera ray passes through the light (from behind, here) and sees
    the lit plane below; without it the light's black back hides the plane. Seen head on, the light is black
    when hidden."""
    xml = looking_down_through_the_light(tmp_path)
    shown = render(tmp_path, xml, type_name, spp=64)
    assert np.all(shown.image == 0.0)
    hidden = render(tmp_path, xml, type_name, spp=4096, hide_emitters=True)
    res = compare_to_value(hidden, A.polygon_light_value(), ALPHA)
    assert res.passed, (res.message, hidden.image[0, 0], A.polygon_light_value())
    up = light_over_plane_from_below(tmp_path)
    assert np.all(render(tmp_path, up, type_name, spp=16, hide_emitters=True).image == 0.0)
    np.testing.assert_allclose(render(tmp_path, up, type_name, spp=16).image[0, 0], A.LE, rtol=1e-6)
    if type_name == "path":   # emitters hidden and no bounce allowed: nothing at all (as Mitsuba 3.9)
        assert np.all(render(tmp_path, xml, type_name, spp=16, hide_emitters=True, max_depth=1).image == 0.0)


@pytest.mark.parametrize("type_name", ["path", "direct"])
def test_hide_emitters_hides_the_environment(tmp_path, type_name):
    """Camera rays that escape see a constant environment unless it is hidden; the plane it lights stays lit."""
    xml = A.polygon_light_scene(tmp_path, "path_mis").replace(
        "</scene>", '<emitter type="constant"><color name="radiance" value="0.25"/></emitter></scene>')
    sky = xml.replace(f'target="{",".join(f"{v:.9g}" for v in A.X0)}"', 'target="5,0.1,3"')
    assert sky != xml
    shown = render(tmp_path, sky, type_name, spp=16)
    np.testing.assert_allclose(shown.image, 0.25, rtol=1e-6)
    assert np.all(render(tmp_path, sky, type_name, spp=16, hide_emitters=True).image == 0.0)
    lit = render(tmp_path, xml, type_name, spp=256, hide_emitters=True)
    assert np.all(lit.image > 0.05)


# --- volpath, volpathmis, prb, prbvolpath on surfaces ---------------------------------------------------------------

@pytest.mark.parametrize("type_name", ["volpath", "volpathmis", "prb", "prbvolpath", "ptracer"])
@pytest.mark.parametrize("max_depth", [2, -1])
def test_volumetric_and_replay_path_tracers_give_the_furnace_series(tmp_path, type_name, max_depth):
    """Without media (and without null events) they estimate what path does: the furnace's series."""
    rho = 0.5
    expected = 1 / (1 - rho) if max_depth == -1 else 1 + rho
    film = render(tmp_path, A.furnace_scene(tmp_path, "path_mis", rho=rho), type_name, spp=1024, max_depth=max_depth)
    res = compare_mean_to_value(film, expected, ALPHA)
    assert res.passed, (type_name, max_depth, res.message, film.image.mean(), expected)


def test_prb_renders_exactly_as_path(tmp_path):
    xml = A.polygon_light_scene(tmp_path, "path_mis")
    a = render(tmp_path, xml, "path", spp=16, max_depth=3, rr_depth=2)
    b = render(tmp_path, xml, "prb", spp=16, max_depth=3, rr_depth=2)
    np.testing.assert_array_equal(a.image, b.image)


def test_volpath_hide_emitters_hides_only_what_the_camera_sees_first(tmp_path):
    """volpath's hide_emitters: the light's back (black) still hides the plane, unlike path's pass-through;
    head on, the light is black; escaping camera rays see no sky."""
    xml = looking_down_through_the_light(tmp_path)
    assert np.all(render(tmp_path, xml, "volpath", spp=16, hide_emitters=True).image == 0.0)
    up = light_over_plane_from_below(tmp_path)
    assert np.all(render(tmp_path, up, "volpath", spp=16, hide_emitters=True).image == 0.0)
    np.testing.assert_allclose(render(tmp_path, up, "volpathmis", spp=16).image[0, 0], A.LE, rtol=1e-6)


def test_ptracer_renders_the_path_image_and_says_so(caplog):
    """Mitsuba's particle tracer is rendered by path with its max_depth and rr_depth: the same image for the same
    seed, and a warning at the integrator's line (the twin integrator_ptracer holds it to Mitsuba's ptracer)."""
    from pathlib import Path
    scene_file = Path(__file__).resolve().parent / "mitsuba" / "scenes" / "integrator_ptracer.xml"
    with caplog.at_level("WARNING", logger="clrender"):
        ptracer = clrender.load_scene(scene_file, spp="8")
    warned = [r.getMessage() for r in caplog.records if "ptracer" in r.getMessage()]
    assert len(warned) == 1 and f"{scene_file}:8:" in warned[0] and "path tracer" in warned[0], warned
    caplog.clear()
    with caplog.at_level("WARNING", logger="clrender"):
        path = clrender.load_scene(scene_file, spp="8", integrator="path")
    assert not caplog.records
    a, b = clrender.render(ptracer, seed=5), clrender.render(path, seed=5)
    assert (ptracer.integrator.max_depth, ptracer.integrator.rr_depth) == (3, 2)
    np.testing.assert_array_equal(a.image, b.image)
    assert a.image.mean() > 0


def test_ptracer_refuses_hide_emitters():
    with pytest.raises(SceneError, match="hide_emitters is not supported with ptracer"):
        mitsuba_integrator("ptracer", hide_emitters=True)


def test_prb_refuses_hide_emitters():
    with pytest.raises(SceneError, match="hide_emitters is not supported with prb"):
        mitsuba_integrator("prb", hide_emitters=True)


# --- direct: sample counts ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("counts", [dict(), dict(emitter_samples=4, bsdf_samples=0),
                                    dict(emitter_samples=0, bsdf_samples=4), dict(emitter_samples=3, bsdf_samples=2),
                                    dict(shading_samples=2)])
def test_direct_sample_counts_converge_to_the_same_image(tmp_path, counts):
    film = render(tmp_path, A.polygon_light_scene(tmp_path, "path_mis"), "direct", spp=2048, **counts)
    res = compare_to_value(film, A.polygon_light_value(), ALPHA)
    assert res.passed, (counts, res.message, film.image[0, 0], A.polygon_light_value())


def test_direct_sample_counts_reach_the_kernel(tmp_path):
    """More samples per pixel sample: lower variance (emitter-only vs BSDF-only differ most)."""
    xml = A.polygon_light_scene(tmp_path, "path_mis")
    one = render(tmp_path, xml, "direct", spp=512, emitter_samples=1, bsdf_samples=0)
    eight = render(tmp_path, xml, "direct", spp=512, emitter_samples=8, bsdf_samples=0)
    assert eight.variance().mean() < 0.3 * one.variance().mean()


def test_direct_delta_lights_count_once_per_emitter_sample(tmp_path):
    """Mitsuba 3.9's direct gives an emitter sample of a delta light weight 1, not 1/emitter_samples (measured:
    a point light with emitter_samples=4 renders 4x as bright as with 1); we render Mitsuba's image. BSDF
    sampling cannot find a point light: emitter_samples=0 is black."""
    xml = A.point_light_scene(tmp_path, "path_mis")
    for n in (1, 4):
        film = render(tmp_path, xml, "direct", spp=4, emitter_samples=n)
        np.testing.assert_allclose(film.image, np.broadcast_to(n * A.point_light_value(), film.image.shape),
                                   rtol=2e-4)
    assert np.all(render(tmp_path, xml, "direct", spp=16, emitter_samples=0, bsdf_samples=2).image == 0.0)


# --- aov -----------------------------------------------------------------------------------------------------------

NULL_SCENE = """<scene version="3.0.0"><integrator type="{integrator}"/>
    <sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/>
        </transform><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/>
        <rfilter type="box"/></film></sensor>{extra}
    <shape type="rectangle"><transform name="to_world"><scale value="3"/></transform>
        <emitter type="area"><rgb name="radiance" value="2"/></emitter>{bsdf}</shape></scene>"""
NULL = '<bsdf type="null"/>'
HALF_MASK = '<bsdf type="mask"><float name="opacity" value="0.5"/><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf></bsdf>'
WALL = ('<shape type="rectangle"><transform name="to_world"><scale value="9"/><translate z="-1"/></transform>'
        '<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf></shape>')
DIRECTIONAL = '<emitter type="directional"><vector name="direction" value="0, 0, -1"/></emitter>'


@pytest.mark.parametrize("integrator, bsdf, extra, value", [
    ("path", NULL, "", 0.0),                     # met only a pass-through, no environment: Mitsuba keeps nothing
    ("path", NULL, DIRECTIONAL, 0.0),            # a directional light is no environment
    ("path", NULL, '<emitter type="constant"><rgb name="radiance" value="0"/></emitter>', 2.0),
    ("path", NULL, WALL, 2.0),                   # the path ends on a real surface behind the light
    ("path", HALF_MASK, "", 1.0),                # kept where the mask's black child was sampled
    ("path", '<bsdf type="thindielectric"/>', WALL, 2.0),
    ("direct", NULL, "", 2.0),                   # Mitsuba's direct keeps every camera ray
], ids=["null", "null, directional", "null, environment", "null, wall behind", "half mask", "thin glass, wall",
        "direct"])
def test_null_bsdf_and_paths_that_meet_no_surface(tmp_path, integrator, bsdf, extra, value):
    """Mitsuba's null BSDF (Blender's exporter puts one on every area light; once an unknown plugin here) passes
    light straight through. Mitsuba 3.9.1's path keeps a path's radiance only if the scene has an environment or the
    path met a surface it did not pass straight through (a null or mask pass-through, a thin dielectric's
    transmission): an emitting null quad against nothing renders black there (each value read off Mitsuba)."""
    (tmp_path / "s.xml").write_text(NULL_SCENE.format(integrator=integrator, bsdf=bsdf, extra=extra))
    film = clrender.render(clrender.load_scene(tmp_path / "s.xml"), spp=256, seed=2)
    res = compare_mean_to_value(film, value, ALPHA)
    assert res.passed, (res.message, film.image.mean())


def test_aovs_of_the_plane(tmp_path):
    """Every pixel sees the plane near X0 (fov 0.05 degrees): depth = |camera - X0| less the near clip distance
    (Mitsuba's camera rays start on the near plane; Nori's default near clip is 1e-4, so make it 0.25 here),
    position = X0, both normals = +z (the plane's winding); 0 where rays escape."""
    xml = A.polygon_light_scene(tmp_path, "path_mis").replace(
        '<float name="fov"', '<float name="nearClip" value="0.25"/><float name="fov"')
    origin = np.array([2.5, 0.1, 1.5])
    expected = {"depth": np.full(3, np.linalg.norm(origin - A.X0) - 0.25), "position": A.X0,
                "geo_normal": np.array([0.0, 0.0, 1.0]), "sh_normal": np.array([0.0, 0.0, 1.0])}
    for kind, value in expected.items():
        film = render(tmp_path, xml, "aov", spp=4, aovs=f"out:{kind}")
        np.testing.assert_allclose(film.image, np.broadcast_to(value, film.image.shape), atol=5e-3, err_msg=kind)
    sky = xml.replace(f'target="{",".join(f"{v:.9g}" for v in A.X0)}"', 'target="5,0.1,3"')
    assert np.all(render(tmp_path, sky, "aov", spp=4, aovs="dd.y:depth").image == 0.0)


def test_depth_integrator_is_aovs_depth(tmp_path):
    """Mitsuba's `depth` renders what `aov` renders for `dd.y:depth` (as Mitsuba 3.9.1 does)."""
    xml = A.polygon_light_scene(tmp_path, "path_mis")
    a = render(tmp_path, xml, "depth", spp=4)
    b = render(tmp_path, xml, "aov", spp=4, aovs="dd.y:depth")
    np.testing.assert_array_equal(a.image, b.image)
    assert a.image.max() > 0


# --- errors --------------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("type_name,props,message", [
    ("path", dict(max_depth=-2), "max_depth must be -1"),
    ("path", dict(rr_depth=0), "rr_depth must be at least 1"),
    ("path", dict(maxDepth=3), "maxDepth"),
    ("direct", dict(shading_samples=2, emitter_samples=1), "either shading_samples"),
    ("direct", dict(emitter_samples=0, bsdf_samples=0), "at least one emitter or BSDF sample"),
    ("direct", dict(bsdf_samples=-1), "bsdf_samples must be between 0"),
    ("aov", dict(aovs="dd.y:depth,nn:sh_normal"), "one RGB image"),
    ("aov", dict(aovs="a:albedo"), "Mitsuba AOV type clrender does not render"),
    ("aov", dict(aovs="depth"), "not a <name>:<type> pair"),
    ("aov", dict(), "aovs"),
])
def test_bad_parameters_are_clear_errors(type_name, props, message):
    with pytest.raises(SceneError, match=message):
        mitsuba_integrator(type_name, **props)


def test_nori_names_stay_nori():
    """Mitsuba's `path` does not exist in Nori files, and Nori's `direct` is still Nori's there."""
    with pytest.raises(SceneError, match="unknown integrator type 'path'"):
        instantiate("integrator", "path")
    assert type(instantiate("integrator", "direct")).__name__ == "Direct"


# --- moment: the nested integrator's image and its second moment as EXR channels --------------------------------

def moment_scene(tmp_path, rfilter='<rfilter type="box"/>', nested='<integrator type="path"/>'):
    """A 5 x 5 pinhole view, 90 degrees wide, of an emitting rectangle (radiance 2) on black whose edge projects onto
    the middle of the centre column: there a box-filtered pixel's samples are 2 or 0 with probability 1/2 each, so
    its first moment is 1 and its second 2 (not 1, the first squared); the columns on either side are exactly 2 and
    0 (second moments 4 and 0)."""
    p = tmp_path / "moment.xml"
    p.write_text(f'<scene version="3.0.0"><integrator type="moment">{nested}</integrator>'
                 '<sensor type="perspective"><float name="fov" value="90"/><transform name="to_world"><lookat '
                 'origin="0, 0, 1" target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm">'
                 f'<integer name="width" value="5"/><integer name="height" value="5"/>{rfilter}</film></sensor>'
                 '<shape type="rectangle"><transform name="to_world"><scale value="5, 5, 1"/><translate value="5, 0, 0"/>'
                 '</transform><emitter type="area"><rgb name="radiance" value="2"/></emitter></shape></scene>')
    return p


def test_moment_writes_the_second_moment_beside_the_image(tmp_path):
    """Mitsuba 3.9.1's m2 with a box filter is each pixel's mean of its samples' squares (of X, Y, Z; ours of R, G,
    B: the same numbers for this grey scene), which the film's sum((w L)^2) / sum(w) is when every w is 1. Checked
    per pixel against the closed form (z-test; exact where the pixel is), and the channels' names as Mitsuba's
    (`m2_` + the nested integrator's name, `_arg_0` when it has none)."""
    import OpenEXR

    scene = clrender.load_scene(moment_scene(tmp_path))
    assert scene.integrator.kernel == "path_mitsuba" and scene.moment_channels == "m2__arg_0"
    spp = 256
    film = clrender.render(scene, spp=spp, seed=3)
    column = np.array([0.0, 0.0, 1.0, 2.0, 2.0])   # Mitsuba's +x is the image's left: the rectangle (x > 0) is right
    m1 = np.broadcast_to(column[None, :, None], (5, 5, 3))
    assert compare_to_value(film, m1, ALPHA).passed
    film.write(tmp_path / "out.exr")
    with OpenEXR.File(str(tmp_path / "out.exr")) as f:
        ch = f.channels()
        names = sorted(c.name for c in f.header()["channels"])
        m2 = np.array(ch["m2__arg_0"].pixels, np.float64)
        np.testing.assert_array_equal(np.array(ch["RGB"].pixels), film.image)
    assert names == ["B", "G", "R", "m2__arg_0.B", "m2__arg_0.G", "m2__arg_0.R"]
    expected = m1 ** 2 + np.where(m1 == 1.0, 1.0, 0.0)          # E[L^2] = mean^2 + variance (1 at the edge)
    var = np.where(m1 == 1.0, 4.0 / spp, 0.0)                   # L^2 is 0 or 4, each with probability 1/2
    result = _ztest(m2 - expected, var, ALPHA, "m2 vs closed form")
    assert result.passed, result.message


def test_moment_names_and_filters(tmp_path, caplog):
    """A named nested integrator names the channels; a filter other than box leaves them out with a warning (the
    film's sum((w L)^2) is Mitsuba's sum(w L^2) only where every w is 1) and the image is still rendered."""
    import logging

    import OpenEXR

    named = clrender.load_scene(moment_scene(tmp_path, nested='<integrator type="direct" name="d"/>'))
    assert named.moment_channels == "m2_d" and named.integrator.kernel == "direct_mitsuba"
    with caplog.at_level(logging.WARNING, logger="clrender"):
        scene = clrender.load_scene(moment_scene(tmp_path, rfilter='<rfilter type="gaussian"/>'))
    assert scene.moment_channels is None
    assert any("only the first moment" in r.getMessage() and "gaussian" in r.getMessage() for r in caplog.records)
    clrender.render(scene, spp=4, seed=1).write(tmp_path / "g.exr")
    with OpenEXR.File(str(tmp_path / "g.exr")) as f:
        assert sorted(f.channels()) == ["RGB"]
    with pytest.raises(SceneError, match="needs a nested <integrator>") as e:
        clrender.load_scene(moment_scene(tmp_path, nested=""))
    assert e.value.location.file.endswith("moment.xml")


def test_aov_with_a_nested_integrator_renders_that_one(tmp_path, caplog):
    """Mitsuba 3.9.1's aov with a nested integrator: the image is the nested integrator's (the emitter edge scene's
    0, 0, 1, 2, 2 columns, z-tested), and `clrender render` writes each AOV clrender renders beside it under
    Mitsuba 3.9.1's names (`dd.y.T` for a depth, `nn.X/Y/Z`), each exactly the aov integrator's own render with the same
    samples; a type clrender does not render is left out with a warning; a malformed AOV is an error, and a second
    nested integrator too."""
    import logging

    import OpenEXR

    from clrender.cli import main

    def aov_scene(aovs, nested='<integrator type="path"/>'):
        p = moment_scene(tmp_path, nested=nested)
        p.write_text(p.read_text().replace('<integrator type="moment">',
                                           f'<integrator type="aov"><string name="aovs" value="{aovs}"/>'))
        return p

    with caplog.at_level(logging.WARNING, logger="clrender"):
        scene = clrender.load_scene(aov_scene("nn:sh_normal, dd.y:depth, a:albedo"))
    assert scene.integrator.kernel == "path_mitsuba" and scene.moment_channels is None
    assert scene.aovs == [("nn", "sh_normal"), ("dd.y", "depth")]
    assert any("does not render the AOVs a:albedo" in r.getMessage() for r in caplog.records)
    film = clrender.render(scene, spp=256, seed=5)
    assert compare_to_value(film, np.broadcast_to(np.array([0.0, 0.0, 1.0, 2.0, 2.0])[None, :, None], (5, 5, 3)),
                            ALPHA).passed
    assert main(["render", str(aov_scene("nn:sh_normal, dd.y:depth")), "-q", "-o", str(tmp_path / "a.exr"),
                 "--spp", "16", "--seed", "7"]) == 0
    with OpenEXR.File(str(tmp_path / "a.exr")) as f:
        names = sorted(c.name for c in f.header()["channels"])
        ch = {k: np.asarray(c.pixels) for k, c in f.channels().items()}
    assert names == ["B", "G", "R", "dd.y.T", "nn.X", "nn.Y", "nn.Z"]
    for name, kind in (("dd.y", "depth"), ("nn", "sh_normal")):
        one = clrender.load_scene(aov_scene(f"{name}:{kind}"))
        one.integrator = mitsuba_integrator("aov", aovs=f"{name}:{kind}")
        want = clrender.render(one, spp=16, seed=7).image
        got = ch[f"{name}.T"] if kind == "depth" else np.stack([ch[f"{name}.{c}"] for c in "XYZ"], axis=-1)
        np.testing.assert_array_equal(got, want[..., 0] if kind == "depth" else want)
    assert ch["nn.Z"].max() == 1.0 and ch["dd.y.T"].max() > 0
    with pytest.raises(SceneError, match="'nn:normal' is not a <name>:<type> pair"):
        clrender.load_scene(aov_scene("nn:normal"))
    with pytest.raises(SceneError, match="takes one nested integrator, got 2"):
        clrender.load_scene(aov_scene("dd.y:depth", '<integrator type="path"/><integrator type="direct"/>'))
