"""Reading and packing participating media (Mitsuba 3 scenes): <medium type="homogeneous"> with its parameters and
Mitsuba's defaults, a nested <phase>, media named by <ref name="interior|exterior"> or nested in shapes, the camera's
medium, the shared `media` and `phases` tables, and the located refusals of what is not supported (a volume in a
homogeneous medium, a medium where none belongs)."""
import numpy as np
import pytest

from clrender import plugins  # noqa: F401
from clrender.device.layout import NONE
from clrender.errors import SceneError
from clrender.pack import _pack_media, PackContext
from clrender.scene.xmlparser import parse_string
from clrender.scene.registry import create

HEAD = '<scene version="3.0.0">'
SENSOR = ('<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>'
          '<integer name="height" value="6"/></film>{}</sensor>')


def load(body: str, sensor_medium: str = ""):
    return create(parse_string(f"{HEAD}{SENSOR.format(sensor_medium)}{body}</scene>", "m.xml"))


def err(body: str, line: int, *fragments: str):
    with pytest.raises(SceneError) as e:
        load(body)
    assert e.value.location is not None and e.value.location.file == "m.xml" and e.value.location.line == line, \
        str(e.value)
    for f in fragments:
        assert f in str(e.value), str(e.value)
    return e.value


def pack_media(scene):
    from clrender.device import layout
    rows = layout.zeros("Shape", len(scene.shapes))
    ctx = PackContext()
    try:
        _pack_media(scene, ctx, rows)
    except SceneError:   # stage 1: read, not yet rendered
        pass
    return rows, ctx.array("media")[:ctx.size("media")], ctx.array("phases")[:ctx.size("phases")], ctx.camera_medium


def test_defaults_are_mitsubas():
    """sigma_t 1, albedo 0.75, scale 1, sample_emitters and has_spectral_extinction true, isotropic phase; hg's g
    0.8 (Mitsuba 3.9.1's src/phase/hg.cpp)."""
    s = load('<shape type="sphere"><medium type="homogeneous" name="interior"/></shape>')
    m = s.shapes[0].interior
    assert np.all(m.sigma_t == 1) and np.all(m.albedo == 0.75) and m.sample_emitters and m.spectral
    assert type(m.phase).__name__ == "Isotropic" and s.shapes[0].exterior is None
    s = load('<shape type="sphere"><medium type="homogeneous" name="exterior"><phase type="hg"/></medium></shape>')
    assert s.shapes[0].exterior.phase.g == pytest.approx(0.8)


def test_parameters_scale_and_rows():
    s = load('<medium type="homogeneous" id="fog"><rgb name="sigma_t" value="1, 2, 3"/><float name="scale" '
             'value="2"/><rgb name="albedo" value="0.1, 0.2, 0.3"/><boolean name="sample_emitters" value="false"/>'
             '<phase type="hg"><float name="g" value="-0.4"/></phase></medium>'
             '<shape type="sphere"><ref id="fog" name="interior"/></shape>'
             '<shape type="sphere"><ref id="fog" name="exterior"/><medium type="homogeneous" name="interior">'
             '<float name="sigma_t" value="5"/></medium></shape>', '<ref id="fog"/>')
    rows, media, phases, cam = pack_media(s)
    from clrender.device import layout
    # the tables keep the kernels' row layout (NumPy's concatenate dropped the Phase row's padding once)
    assert phases.dtype == layout.dtype("Phase") and media.dtype == layout.dtype("Medium")
    # a ref under a name is a medium of its own (same values), its phase function the declared one's
    assert len(media) == 4 and len(phases) == 2
    np.testing.assert_allclose(media[0]["homogeneous"]["sigma_t"][:3], [2, 4, 6])
    np.testing.assert_allclose(media[0]["homogeneous"]["albedo"][:3], [0.1, 0.2, 0.3], rtol=1e-6)
    from clrender.device import dispatch
    flags = dispatch.flag_defines()
    assert not media[0]["flags"] & flags["MEDIUM_SAMPLE_EMITTERS"] and media[0]["flags"] & flags["MEDIUM_HOMOGENEOUS"]
    assert media[1]["flags"] & flags["MEDIUM_SAMPLE_EMITTERS"]
    np.testing.assert_allclose(media[1]["homogeneous"]["sigma_t"][:3], 5)
    assert phases[media[0]["phase"]]["hg"]["g"] == pytest.approx(-0.4)
    assert media[0]["phase"] == media[2]["phase"] == media[3]["phase"] != media[1]["phase"]
    assert rows[0]["interior"] == 0 and rows[0]["exterior"] == NONE
    assert rows[1]["interior"] == 1 and rows[1]["exterior"] == 2
    assert cam == 3 and media[3]["homogeneous"]["sigma_t"][0] == 2


def test_a_scene_without_media_packs_none():
    rows, media, phases, cam = pack_media(load('<shape type="sphere"/>'))
    assert len(media) == 0 and cam == NONE and rows[0]["interior"] == NONE and rows[0]["exterior"] == NONE


def test_refusals_are_located():
    err('<shape type="sphere"><medium type="homogeneous">\n<volume type="constvolume" name="sigma_t"/>'
        '</medium></shape>', 2, "sigma_t is one value everywhere", 'type="heterogeneous"')
    err('<shape type="sphere"><medium type="homogeneous">\n<volume type="constvolume" name="density"/>'
        '</medium></shape>', 2, 'name="albedo"', "'density'")
    err('<shape type="sphere"><medium type="homogeneous">\n<volume type="constvolume" name="albedo">'
        '<float name="value" value="2"/></volume></medium></shape>', 2, "albedo must lie in [0, 1]")
    err('<shape type="sphere">\n<medium type="homogeneous"/></shape>', 2, 'name="interior"')
    err('<shape type="sphere">\n<medium type="homogeneous" name="inside"/></shape>', 2, 'name="interior"', "'inside'")
    err('<bsdf type="diffuse">\n<medium type="homogeneous"/></bsdf>', 2, "cannot be nested", "<shape>")
    err('<shape type="sphere"><medium type="homogeneous" name="interior">\n<phase type="rayleigh"/></medium></shape>',
        2, "unknown phase type 'rayleigh'", "hg", "isotropic")
    err('<shape type="sphere"><medium type="homogeneous" name="interior">\n<phase type="hg"><float name="g" '
        'value="1"/></phase></medium></shape>', 2, "(-1, 1)")
    err('<shape type="sphere"><medium type="homogeneous" name="interior">\n<float name="albedo" value="1.5"/>'
        '</medium></shape>', 2, "albedo must lie in [0, 1]")
    err('<shape type="sphere"><medium type="homogeneous" name="interior">\n<rgb name="sigma_t" value="1, -1, 1"/>'
        '</medium></shape>', 2, "sigma_t must be non-negative")
    err('<shape type="sphere"><medium type="homogeneous" name="interior">\n<float name="density" value="1"/>'
        '</medium></shape>', 2, "density")


# ------------------------------------------------------------------------------------------------ renders
from .media_common import (absorbing_slab, absorbing_slab_length, furnace, medium_xml, render_xml,  # noqa: E402
                           single_scattering_slab, single_scattering_value)
from clrender.testing.stats import compare_to_value  # noqa: E402

SIGMA = (0.5, 1.0, 2.0)
RADIANCE = (2.0, 1.0, 0.5)


@pytest.mark.plugin("homogeneous", "render")
@pytest.mark.parametrize("kind,camera_inside", [("volpath", False), ("volpathmis", True)])
def test_absorbing_slab_is_beer_lambert(tmp_path, kind, camera_inside):
    """A camera looking through an absorbing slab (albedo 0, colour extinction) at an emitter of radiance L sees
    L exp(-sigma_t d) in every pixel (per-pixel z-test); from outside (two null boundaries crossed) and from inside
    (the camera's medium)."""
    depth = 1.5
    film = render_xml(tmp_path, absorbing_slab(SIGMA, RADIANCE, depth, kind, camera_inside=camera_inside))
    expected = np.asarray(RADIANCE) * np.exp(-np.asarray(SIGMA) * absorbing_slab_length(depth, camera_inside))
    r = compare_to_value(film, expected)
    assert r.passed, f"{r.message}; image mean {film.image.mean(axis=(0, 1))}, expected {expected}"


@pytest.mark.plugin("homogeneous", "render")
@pytest.mark.parametrize("phase,camera_inside,sample_emitters", [
    ('<phase type="isotropic"/>', False, True), ('<phase type="hg"><float name="g" value="0.7"/></phase>', True, True),
    ('<phase type="hg"><float name="g" value="-0.5"/></phase>', False, True),
    ('<phase type="isotropic"/>', False, False),
    ('<phase type="hg"><float name="g" value="0.7"/></phase>', True, False)])
def test_furnace_radiance_is_the_emission(tmp_path, phase, camera_inside, sample_emitters):
    """A non-absorbing medium (albedo 1, colour extinction) in a constant environment of radiance 1 behind a null
    boundary: every pixel is 1, whatever the phase function (per-pixel z-test), seen from outside or inside. Also
    with sample_emitters false, where the phase sample is the only way out: what it finds counts whole, as in
    Mitsuba's volpath (it used to be MIS-weighted against an emitter sample never taken, giving about 0.6)."""
    film = render_xml(tmp_path, furnace((1.0, 2.0, 4.0), phase, camera_inside=camera_inside,
                                        sample_emitters=sample_emitters))
    r = compare_to_value(film, 1.0)
    assert r.passed, f"{r.message}; image mean {film.image.mean(axis=(0, 1))}"


def iso(cos):
    return 1 / (4 * np.pi)


@pytest.mark.plugin("homogeneous", "render")
@pytest.mark.parametrize("kind,decoy", [("volpath", False), ("volpathmis", True)])
def test_single_scattering_against_quadrature(tmp_path, kind, decoy):
    """A thin slab lit by a directional light, max_depth 2 (one scattering event), seen from above: each pixel is
    the single-scattering integral over depth (scipy quadrature); at max_depth 3 the image is brighter (double
    scattering), so the depth limit is what decides. With a decoy: a far-away sphere of another medium and phase
    function declared first, so the slab's medium and phase function are second rows of their tables."""
    args = ((0.8, 1.6, 3.2), (0.9, 0.6, 0.3), '<phase type="isotropic"/>', 0.7, 35.0, (3.0, 2.0, 1.0))
    expected = single_scattering_value(args[0], args[1], iso, *args[3:])
    xml = single_scattering_slab(*args, kind=kind)
    if decoy:
        i = xml.index('<shape type="cube">')
        xml = (xml[:i] + '<shape type="sphere"><point name="center" value="90, 0, 0"/><bsdf type="null"/>'
               + medium_xml((4, 2, 1), 0.5, '<phase type="hg"><float name="g" value="0.3"/></phase>',
                            name="interior") + '</shape>' + xml[i:])
    film = render_xml(tmp_path, xml)
    r = compare_to_value(film, expected)
    assert r.passed, f"{r.message}; image mean {film.image.mean(axis=(0, 1))}, expected {expected}"
    deeper = render_xml(tmp_path, single_scattering_slab(*args, kind=kind, max_depth=3, spp=256), seed=2)
    assert not compare_to_value(deeper, expected).passed


def test_volpath_on_the_wavefront_driver_is_refused(tmp_path):
    import clrender
    from clrender.executors import DriverError

    path = tmp_path / "slab.xml"
    path.write_text(absorbing_slab(SIGMA, RADIANCE, 1.0, spp=4))
    with pytest.raises(DriverError, match="participating media"):
        clrender.render(clrender.load_scene(path), driver="wavefront")


@pytest.mark.plugin("homogeneous", "render")
def test_path_ignores_media_as_mitsuba_does(tmp_path):
    """Mitsuba 3.9.1's `path` has no notion of media (checked by hand: it renders this scene as L): the camera sees the
    emitter through the slab unattenuated."""
    film = render_xml(tmp_path, absorbing_slab(SIGMA, RADIANCE, 1.5, "path", spp=16))
    np.testing.assert_allclose(film.image, np.broadcast_to(RADIANCE, film.image.shape), rtol=1e-5)


def test_prbvolpath_with_media_is_refused(tmp_path):
    import clrender
    from clrender.pack import pack_scene

    path = tmp_path / "slab.xml"
    path.write_text(absorbing_slab(SIGMA, RADIANCE, 1.0, "prbvolpath", spp=4))
    with pytest.raises(SceneError, match="volpath") as e:
        pack_scene(clrender.load_scene(path))
    assert e.value.location is not None and e.value.location.line == 1


@pytest.mark.plugin("homogeneous", "render")
def test_the_cameras_medium_starts_at_the_near_clip_plane(tmp_path):
    """A perspective camera inside an absorbing medium with a far near clip: the medium starts at the near plane,
    as Mitsuba's rays start there (a narrow view, so every ray is axial to 1e-5)."""
    from .media_common import persp_sensor

    depth, near = 1.5, 0.5
    xml = absorbing_slab(SIGMA, RADIANCE, depth, camera_inside=True)
    start = xml.index("<sensor"), xml.index("</sensor>") + len("</sensor>")
    sensor = persp_sensor((0, 0, depth / 2 - 0.25), (0, 0, -10), 0.5, 8, 1024, '<ref id="slab"/>')
    sensor = sensor.replace('<float name="fov"', f'<float name="near_clip" value="{near}"/><float name="fov"')
    film = render_xml(tmp_path, xml[:start[0]] + sensor + xml[start[1]:])
    expected = np.asarray(RADIANCE) * np.exp(-np.asarray(SIGMA) * (depth - 0.25 - near))
    r = compare_to_value(film, expected)
    assert r.passed, f"{r.message}; image mean {film.image.mean(axis=(0, 1))}, expected {expected}"


@pytest.mark.plugin("homogeneous", "render")
def test_shadow_rays_cross_a_thin_dielectric(tmp_path):
    """The single-scattering slab bounded by a thindielectric sheet (eta 1.5) instead of null: the camera ray gets
    in with the sheet's transmittance at normal incidence, the light's shadow ray with its transmittance at the
    light's angle (Mitsuba's eval_null_transmission); reflections off the sheet count as bounces and so end there
    at max_depth 2. Each pixel: single scattering times T(0) T(theta_light)."""
    from .media_common import thin_sheet_transmittance

    theta = 40.0
    args = ((1.0, 1.5, 2.5), 0.8, '<phase type="isotropic"/>', 0.6, theta, (3.0, 2.0, 1.0))
    sheet = thin_sheet_transmittance(1.0, 1.5) * thin_sheet_transmittance(np.cos(np.radians(theta)), 1.5)
    expected = single_scattering_value(args[0], args[1], iso, *args[3:]) * sheet
    bsdf = '<bsdf type="thindielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>'
    film = render_xml(tmp_path, single_scattering_slab(*args, bsdf=bsdf))
    r = compare_to_value(film, expected)
    assert r.passed, f"{r.message}; image mean {film.image.mean(axis=(0, 1))}, expected {expected}"
