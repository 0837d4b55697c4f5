"""Mitsuba 0.x files (clrender/scene/mitsuba_legacy.py): read as Mitsuba 3.9.1 upgrades them (names, diffuse's
reflectance, the uv offsets and scales), and what we read beyond Mitsuba 3 (lookAt, dropped parameters, old
integrators named). Scenes of our own, written here in both spellings."""
import logging

import numpy as np
import pytest

import clrender
import clrender.plugins  # noqa: F401
from clrender.errors import SceneError
from clrender.scene.mitsuba_legacy import camel_to_snake
from clrender.scene.registry import create
from clrender.scene.xmlparser import parse_string


# Mitsuba 3.9.1's own renames, read off its "unreferenced properties" error for a 0.6 file with these names
@pytest.mark.parametrize("old, new", [("toWorld", "to_world"), ("cropOffsetX", "crop_offset_x"), ("intIOR", "int_ior"),
                                      ("HDRFile", "HDRFile"), ("aBCdE", "a_bcd_e"), ("x2Y", "x2Y"),
                                      ("already_snake", "already_snake"), ("uvScaleUV", "uv_scale_uv")])
def test_names_go_to_snake_case_as_in_mitsuba(old, new):
    assert camel_to_snake(old) == new


def scene_xml(version: str, body: str, sensor: str) -> str:
    return f'<scene version="{version}">{sensor}{body}<emitter type="constant"><rgb name="radiance" value="1"/></emitter></scene>'


SENSOR = ('<integrator type="path"><integer name="{max_depth}" value="4"/><integer name="{rr_depth}" value="2"/>'
          '</integrator><sensor type="perspective"><float name="fov" value="40"/><string name="{fov_axis}" value="y"/>'
          '<float name="{near_clip}" value="0.5"/><transform name="{to_world}">'
          '<{lookat} origin="0, 1, 6" target="0, 0, 0" up="0, 1, 0"/></transform>'
          '<sampler type="independent"><integer name="{sample_count}" value="3"/></sampler>'
          '<film type="hdrfilm"><integer name="width" value="20"/><integer name="height" value="14"/>'
          '<integer name="{crop_offset_x}" value="2"/><integer name="{crop_width}" value="16"/><rfilter type="box"/>'
          '</film></sensor>')
BODY = """
  <texture type="checkerboard" id="check">{uv_check}<rgb name="color0" value="0.1, 0.2, 0.6"/></texture>
  <bsdf type="diffuse" id="plain"><rgb name="{reflectance}" value="0.2, 0.5, 0.3"/></bsdf>
  <bsdf type="diffuse" id="checked"><ref name="{reflectance}" id="check"/></bsdf>
  <bsdf type="roughplastic" id="coat"><float name="{int_ior}" value="1.6"/><string name="distribution" value="ggx"/>
    <float name="alpha" value="0.2"/><rgb name="{diffuse_reflectance}" value="0.6, 0.3, 0.2"/></bsdf>
  <shape type="sphere"><ref id="plain"/></shape>
  <shape type="sphere"><point name="center" x="2.2" y="0" z="0"/><ref id="checked"/></shape>
  <shape type="sphere"><point name="center" x="-2.2" y="0" z="0"/><ref id="coat"/></shape>
  <shape type="rectangle"><transform name="{to_world}"><scale value="5"/><rotate x="1" angle="-90"/>
    <translate y="-1"/></transform><bsdf type="diffuse"><texture type="checkerboard" name="{reflectance}">
    {uv_floor}</texture></bsdf></shape>
"""
#: the same scene's names in Mitsuba 0.x's spelling and in Mitsuba 3's (written out here, not derived)
OLD = dict(max_depth="maxDepth", rr_depth="rrDepth", fov_axis="fovAxis", near_clip="nearClip", to_world="toWorld",
           lookat="lookAt", sample_count="sampleCount", crop_offset_x="cropOffsetX", crop_width="cropWidth",
           reflectance="diffuseReflectance", int_ior="intIOR", diffuse_reflectance="diffuseReflectance",
           uv_check='<float name="uscale" value="4"/><float name="uoffset" value="0.3"/><float name="voffset" '
                    'value="0.25"/>',
           uv_floor='<float name="vscale" value="3"/><float name="uoffset" value="0.1"/>')
NEW = dict(max_depth="max_depth", rr_depth="rr_depth", fov_axis="fov_axis", near_clip="near_clip", to_world="to_world",
           lookat="lookat", sample_count="sample_count", crop_offset_x="crop_offset_x", crop_width="crop_width",
           reflectance="reflectance", int_ior="int_ior", diffuse_reflectance="diffuse_reflectance",
           uv_check='<transform name="to_uv"><translate x="0.3" y="0.25"/><scale x="4" y="1"/></transform>',
           uv_floor='<transform name="to_uv"><translate x="0.1" y="0"/><scale x="1" y="3"/></transform>')


@pytest.mark.parametrize("version", ["0.5.0", "0.6", "1.0.0"])
def test_old_file_renders_as_its_mitsuba3_spelling(version):
    """The same scene in Mitsuba 0.x and Mitsuba 3 spelling renders the very same image (same seed: the same
    samples), pixel for pixel. Mitsuba 3.9.1 itself gave identical images for such a pair (the to_uv spelt out
    as translate-then-scale, Mitsuba's upgrade), and agreed with ours (mean ratio 0.9999 at 1024 spp)."""
    old = create(parse_string(scene_xml(version, BODY.format(**OLD), SENSOR.format(**OLD)), "old.xml"))
    new = create(parse_string(scene_xml("3.0.0", BODY.format(**NEW), SENSOR.format(**NEW)), "new.xml"))
    assert (old.width, old.height, old.sample_count) == (16, 14, 3)
    a = clrender.render(old, spp=3, seed=7).image
    b = clrender.render(new, spp=3, seed=7).image
    assert a.mean() > 0.05 and np.array_equal(a, b)
    # and the checkerboards did move: without the upgrade's to_uv the picture differs
    unmoved = dict(NEW, uv_floor="")
    plain = create(parse_string(scene_xml("3.0.0", BODY.format(**unmoved), SENSOR.format(**NEW)), "new.xml"))
    assert not np.array_equal(clrender.render(plain, spp=3, seed=7).image, b)


def test_to_uv_is_scale_after_translate():
    tex = create(parse_string('<scene version="0.5.0"><texture type="checkerboard" id="t"><float name="uoffset" '
                              'value="0.5"/><float name="uscale" value="2"/><float name="vscale" value="3"/></texture>'
                              '</scene>', "s.xml").children[0])
    assert np.allclose(tex.to_uv, [[2, 0, 1], [0, 3, 0]])   # (u, v) -> (2 (u + 0.5), 3 v)


def err(xml: str, line: int, *fragments: str) -> SceneError:
    with pytest.raises(SceneError) as e:
        create(parse_string(xml, "old.xml"))
    assert e.value.location is not None and e.value.location.line == line, str(e.value)
    for f in fragments:
        assert f in str(e.value), str(e.value)
    return e.value


@pytest.mark.parametrize("kind", ["bdpt", "photonmapper", "mlt", "sppm"])
def test_old_integrators_we_do_not_have_are_named(kind):
    e = err(f'<scene version="0.5.0">\n  <integrator type="{kind}"/></scene>', 2, f"'{kind}'", "not available",
            "path, ")
    assert e.location.col == 21


def test_old_ptracer_is_mitsuba_3s_ptracer(caplog):
    """Mitsuba 3.9.1 reads a 0.6 ptracer as its own (max_depth 3, rr_depth 2 here): rendered by path, with the
    warning, and 0.6-only parameters refused as Mitsuba refuses them."""
    sensor = ('<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/>'
              '<integer name="height" value="4"/></film></sensor><shape type="sphere"><emitter type="area"/></shape>')
    with caplog.at_level("WARNING", logger="clrender"):
        scene = create(parse_string('<scene version="0.6.0"><integrator type="ptracer"><integer name="maxDepth" '
                                    f'value="3"/><integer name="rrDepth" value="2"/></integrator>{sensor}</scene>',
                                    "old.xml"))
    assert (scene.integrator.max_depth, scene.integrator.rr_depth) == (3, 2)
    assert any("ptracer" in r.getMessage() and "path tracer" in r.getMessage() for r in caplog.records)
    err('<scene version="0.6.0">\n<integrator type="ptracer"><integer name="granularity" value="100"/>'
        f'</integrator>{sensor}</scene>', 2, "granularity")


def test_legacy_errors_are_located():
    err('<scene version="0.5.0">\n<texture type="checkerboard"><float name="uscale" value="0"/></texture></scene>',
        2, "uscale")
    err('<scene version="0.5.0">\n<texture type="checkerboard"><float name="uScale" value="2"/>'
        '<transform name="toUV"><scale value="2"/></transform></texture></scene>', 2, "to_uv")
    err('<scene version="0.5.0">\n<bsdf type="plastic"><float name="intIOR" value="1.4"/>\n'
        '<float name="int_ior" value="1.5"/></bsdf></scene>', 3, "given twice")
    # lookAt is an old file's spelling only
    err('<scene version="3.0.0"><shape type="cube"><transform name="to_world">\n<lookAt origin="0,0,1" target="0,0,0"'
        ' up="0,1,0"/></transform></shape></scene>', 2, "Mitsuba 0.x")
    err('<scene\n version="4.0.0"></scene>', 2, "unsupported 'version'")


@pytest.mark.parametrize("kind, extra", [("sobol", '<integer name="scramble" value="3"/>'),
                                         ("halton", '<integer name="scramble" value="-1"/>'), ("hammersley", ""),
                                         ("ldsampler", '<integer name="dimension" value="4"/>')])
def test_old_samplers_render_with_our_stratified_sampler(kind, extra):
    from clrender.pack import pack_scene

    scene = create(parse_string(f'<scene version="0.5.0"><sensor type="perspective"><sampler type="{kind}">'
                                f'<integer name="sampleCount" value="16"/>{extra}</sampler></sensor>'
                                '<shape type="cube"/></scene>', "old.xml"))
    assert scene.sample_count == 16 and pack_scene(scene).sampler == "sobol"


def test_dropped_parameters_warn(caplog):
    xml = ('<scene version="0.6.0"><integrator type="path"><boolean name="strictNormals" value="true"/></integrator>'
           '<sensor type="perspective"><film type="hdrfilm"><boolean name="highQualityEdges" value="true"/>'
           '<boolean name="banner" value="false"/></film></sensor><shape type="cube"/></scene>')
    with caplog.at_level(logging.WARNING, logger="clrender"):
        create(parse_string(xml, "old.xml"))
    assert "'strict_normals' of the Mitsuba 0.x <integrator" in caplog.text
    assert "'high_quality_edges'" in caplog.text and "banner" not in caplog.text   # Mitsuba 3's hdrfilm takes banner
    # in a Mitsuba 3 file they are unused parameters, as Mitsuba 3 says
    with pytest.raises(SceneError, match="strict_normals"):
        create(parse_string(xml.replace("0.6.0", "3.0.0").replace("strictNormals", "strict_normals"), "new.xml"))


# ------------------------------------------------------------------------------------------------- ldrfilm
def ldrfilm(params: str):
    xml = ('<scene version="0.5.0"><sensor type="perspective"><transform name="toWorld"><lookAt origin="0, 0, -3" '
           'target="0, 0, 0" up="0, 1, 0"/></transform>'
           f'<film type="ldrfilm"><integer name="width" value="8"/>'
           f'<integer name="height" value="6"/>{params}<rfilter type="box"/></film></sensor>'
           '<shape type="sphere"><emitter type="area"><rgb name="radiance" value="0.3, 0.6, 0.9"/></emitter></shape>'
           '</scene>')
    return xml, create(parse_string(xml, "old.xml")).camera.film


def test_ldrfilm_takes_an_old_files_parameters():
    _, film = ldrfilm('<string name="fileFormat" value="png"/><string name="pixelFormat" value="rgb"/>'
                      '<float name="gamma" value="2.2"/><float name="exposure" value="1"/>'
                      '<boolean name="banner" value="false"/><string name="tonemapMethod" value="gamma"/>')
    img = np.array([[[0.1, 0.2, 0.8]]], np.float32)
    assert film.tonemap(img).tolist() == [[[round(255 * 0.2 ** (1 / 2.2)), round(255 * 0.4 ** (1 / 2.2)), 255]]]
    from clrender.film import to_srgb8

    _, default = ldrfilm("")                       # gamma -1: the sRGB curve, as our usual PNG
    wide = np.linspace(0, 1.5, 64, dtype=np.float32).reshape(4, 16, 1).repeat(3, axis=-1)
    assert np.array_equal(default.tonemap(wide), to_srgb8(wide))
    with pytest.raises(SceneError, match="tonemap_method"):
        ldrfilm('<string name="tonemapMethod" value="filmic"/>')


def test_ldrfilm_reinhard_keeps_colour_and_maps_the_brightest_to_white():
    _, film = ldrfilm('<string name="tonemapMethod" value="reinhard"/><float name="gamma" value="1"/>')
    img = np.array([[[0.05, 0.1, 0.2], [2.0, 4.0, 8.0], [0.3, 0.3, 0.3]]], np.float32)
    out = film.tonemap(img).astype(np.float64)
    assert out[0, 1].max() == 255                             # burn 0: the largest luminance becomes 1
    for p in (0, 2):                                          # luminance compressed, chromaticity kept
        assert np.allclose(out[0, p] / out[0, p].max(), img[0, p] / img[0, p].max(), atol=2 / out[0, p].max())
    assert out[0, 0].max() < out[0, 2].max() < 255


def test_ldrfilm_png_is_its_tone_mapped_image(tmp_path):
    from PIL import Image

    from clrender.cli import main
    from clrender.film import read_exr, to_srgb8

    xml, _ = ldrfilm('<float name="gamma" value="1"/><float name="exposure" value="1"/>')
    (tmp_path / "s.xml").write_text(xml)
    assert main(["render", str(tmp_path / "s.xml"), "-q", "-o", str(tmp_path / "s.exr"), "--spp", "2"]) == 0
    linear, _ = read_exr(tmp_path / "s.exr")
    png = np.asarray(Image.open(tmp_path / "s.png").convert("RGB"))
    expected = np.clip(2 * linear.astype(np.float64), 0, 1) * 255       # exposure 1, gamma 1
    assert linear.max() > 0.2 and np.abs(png - expected).max() <= 0.5 + 1e-3   # to the rounding of 8 bits
    assert not np.array_equal(png, to_srgb8(linear))                    # not the plain sRGB preview


# ------------------------------------------------------------------------------------------- maxSmoothAngle
CUBE = ("v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
        "vn 0 0 1\n"   # a file normal, which maxSmoothAngle drops
        "f 1//1 4//1 3//1\nf 1//1 3//1 2//1\nf 5//1 6//1 7//1\nf 5//1 7//1 8//1\nf 1//1 2//1 6//1\nf 1//1 6//1 5//1\n"
        "f 4//1 8//1 7//1\nf 4//1 7//1 3//1\nf 1//1 5//1 8//1\nf 1//1 8//1 4//1\nf 2//1 3//1 7//1\nf 2//1 7//1 6//1\n")
# two unit squares meeting at the x = 0 ridge at 20 degrees off flat (their normals 20 degrees apart)
_S, _C = np.sin(np.radians(10)), np.cos(np.radians(10))
RIDGE = (f"v -{_C} 0 -{_S}\nv 0 0 0\nv 0 1 0\nv -{_C} 1 -{_S}\nv {_C} 0 -{_S}\nv {_C} 1 -{_S}\n"
         "f 1 2 3\nf 1 3 4\nf 2 5 6\nf 2 6 3\n")


def crease_mesh(tmp_path, obj: str, angle: str, version: str = "0.5.0", extra: str = ""):
    (tmp_path / "m.obj").write_text(obj)
    xml = (f'<scene version="{version}"><sensor type="perspective"/><shape type="obj"><string name="filename" '
           f'value="{tmp_path / "m.obj"}"/><float name="maxSmoothAngle" value="{angle}"/>{extra}</shape></scene>')
    return create(parse_string(xml, "old.xml")).shapes[0].mesh


def face_normals(mesh) -> np.ndarray:
    p = mesh.positions.astype(np.float64)[mesh.faces]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def test_max_smooth_angle_keeps_creases_sharper_than_it(tmp_path):
    flat = crease_mesh(tmp_path, CUBE, "30")                  # the cube's 90 degree edges are creases
    assert flat.positions.shape == (24, 3)                    # each corner: one vertex per face meeting there
    for corner in range(3):                                   # each vertex normal is its face's normal
        assert np.allclose(flat.normals[flat.faces[:, corner]], face_normals(flat), atol=1e-6)
    round_ = crease_mesh(tmp_path, CUBE, "100")               # no crease: one vertex per corner
    assert round_.positions.shape == (8, 3)
    assert np.allclose(round_.normals, round_.positions / np.sqrt(3), atol=1e-6)   # (+-1, +-1, +-1) / sqrt 3
    smooth = crease_mesh(tmp_path, RIDGE, "25")               # 20 degrees: smooth across the ridge
    ridge = np.nonzero(np.abs(smooth.positions[:, 0]) < 1e-6)[0]
    assert ridge.size == 2 and np.allclose(smooth.normals[ridge], [0, 0, 1], atol=1e-6)
    sharp = crease_mesh(tmp_path, RIDGE, "15")
    assert np.sum(np.abs(sharp.positions[:, 0]) < 1e-6) == 4   # the ridge's two vertices split
    for corner in range(3):
        assert np.allclose(sharp.normals[sharp.faces[:, corner]], face_normals(sharp), atol=1e-6)


def test_max_smooth_angle_with_face_normals_and_errors(tmp_path):
    assert crease_mesh(tmp_path, CUBE, "30", extra='<boolean name="faceNormals" value="true"/>'
                                                   '<boolean name="collapse" value="true"/>').normals is None
    with pytest.raises(SceneError, match="max_smooth_angle must be between"):
        crease_mesh(tmp_path, CUBE, "200")


def test_srgb_of_old_files_is_the_rgb_of_its_linear_values():
    def albedo(version, colour):
        xml = (f'<scene version="{version}"><sensor type="perspective"/><shape type="cube"><bsdf type="diffuse">'
               f'{colour}</bsdf></shape></scene>')
        return create(parse_string(xml, "s.xml")).shapes[0].bsdf.albedo

    # the sRGB curve's values: 128/255 -> 0.2158605, 0.5 -> 0.2140411, 0.02 -> 0.02 / 12.92
    assert np.allclose(albedo("0.5.0", '<srgb name="diffuseReflectance" value="#80ff00"/>'), [0.2158605, 1, 0])
    assert np.allclose(albedo("0.6.0", '<srgb name="reflectance" value="0.5, 0.02, 1"/>'),
                       [0.2140411, 0.02 / 12.92, 1])
    assert np.allclose(albedo("0.6.0", '<srgb name="reflectance" value="0.5"/>'), [0.2140411] * 3)
    err('<scene version="0.5.0"><shape type="cube"><bsdf type="diffuse">\n<srgb name="reflectance" value="#80zz00"/>'
        '</bsdf></shape></scene>', 2, "bad number")
    err('<scene version="3.0.0"><shape type="cube"><bsdf type="diffuse">\n<srgb name="reflectance" value="#808080"/>'
        '</bsdf></shape></scene>', 2, "unknown tag <srgb>", "Mitsuba 0.x")


def test_old_bitmap_settings_carry_over(tmp_path, caplog):
    from PIL import Image

    Image.fromarray(np.full((2, 2, 3), 128, np.uint8)).save(tmp_path / "t.png")

    def bitmap(params):
        xml = (f'<scene version="0.5.0"><texture type="bitmap" id="t"><string name="filename" value="t.png"/>'
               f'\n{params}</texture></scene>')
        return create(parse_string(xml, str(tmp_path / "s.xml")).children[0])

    with caplog.at_level(logging.WARNING, logger="clrender"):
        t = bitmap('<string name="filterType" value="ewa"/><string name="wrapModeU" value="mirror"/>'
                   '<string name="wrapModeV" value="mirror"/><float name="gamma" value="1"/><float name="uscale" value="2"/>')
    assert (t.filter, t.wrap, t.raw) == (0, 1, True) and "MIP-mapped" in caplog.text
    assert np.allclose(t.image, 128 / 255) and np.allclose(t.to_uv, [[2, 0, 0], [0, 1, 0]])
    assert not bitmap('<float name="gamma" value="-1"/>').raw and np.allclose(bitmap("").image, 0.2158605)
    for bad, what in [('<string name="wrapModeU" value="clamp"/><string name="wrapModeV" value="repeat"/>', "differ"),
                      ('<float name="gamma" value="2.2"/>', "gamma 2.2")]:
        with pytest.raises(SceneError, match=what) as e:
            bitmap(bad)
        assert e.value.location.line == 2


def test_each_file_is_upgraded_by_its_own_version(tmp_path):
    """Mitsuba upgrades each object by the version of the file it is written in: an old file included by a new one
    and a new one included by an old one both read."""
    from clrender.scene.xmlparser import parse_file

    (tmp_path / "old.xml").write_text('<scene version="0.5.0"><bsdf type="diffuse" id="a">'
                                      '<rgb name="diffuseReflectance" value="0.25"/></bsdf></scene>')
    (tmp_path / "new.xml").write_text('<scene version="3.0.0"><bsdf type="plastic" id="b">'
                                      '<float name="int_ior" value="1.7"/></bsdf></scene>')
    (tmp_path / "main.xml").write_text('<scene version="0.6.0"><include filename="new.xml"/>'
                                       '<include filename="old.xml"/><sensor type="perspective"/>'
                                       '<shape type="cube"><ref id="a"/></shape><shape type="sphere"><ref id="b"/>'
                                       '<float name="radius" value="0.5"/></shape></scene>')
    scene = create(parse_file(tmp_path / "main.xml"))
    assert scene.shapes[0].bsdf.albedo.tolist() == [0.25] * 3 and scene.shapes[1].bsdf.int_ior == 1.7
    (tmp_path / "new.xml").write_text('<scene version="3.0.0"><bsdf type="plastic" id="b">'
                                      '\n<float name="intIOR" value="1.7"/></bsdf></scene>')   # camelCase in a v3 file
    with pytest.raises(SceneError, match="'intIOR' is not used") as e:
        create(parse_file(tmp_path / "main.xml"))
    assert e.value.location.file == str(tmp_path / "new.xml") and e.value.location.line == 2


@pytest.mark.parametrize("wrapper", ["adaptive", "irrcache"])
def test_wrapping_integrators_render_as_the_one_they_wrap(wrapper, caplog):
    inner = '<integrator type="path"><integer name="maxDepth" value="3"/></integrator>'
    xml = (f'<scene version="0.5.0"><integrator type="{wrapper}"><float name="maxError" value="0.05"/>{inner}'
           '</integrator><sensor type="perspective"/><shape type="cube"/></scene>')
    with caplog.at_level(logging.WARNING, logger="clrender"):
        wrapped = create(parse_string(xml, "old.xml")).integrator
    plain = create(parse_string(f'<scene version="0.5.0">{inner}<sensor type="perspective"/><shape type="cube"/>'
                                '</scene>', "old.xml")).integrator
    assert type(wrapped) is type(plain) and vars(wrapped).keys() == vars(plain).keys()
    assert wrapped.max_depth == plain.max_depth == 3 and "max_error" in caplog.text
    err(f'<scene version="0.5.0">\n<integrator type="{wrapper}"/></scene>', 2, "must hold one nested <integrator>")


#: a camera inside a homogeneous medium looking at an emitting sphere through it (lajolla's volpath tests are such
#: scenes); {medium} is the medium's parameters in one spelling or the other
MEDIUM_SCENE = """<scene version="{version}">
  <integrator type="volpath"><integer name="{max_depth}" value="3"/></integrator>
  <medium type="homogeneous" id="fog">{medium}<phase type="hg"><float name="g" value="0.3"/></phase></medium>
  <shape type="sphere"><float name="radius" value="0.5"/><emitter type="area"><rgb name="radiance" value="2, 1, 3"/>
    </emitter><bsdf type="diffuse"><rgb name="reflectance" value="0.3"/></bsdf><ref name="exterior" id="fog"/></shape>
  <shape type="sphere"><point name="center" x="0.6" y="0.4" z="0.6"/><float name="radius" value="0.2"/>
    <bsdf type="diffuse"/><ref name="exterior" id="fog"/></shape>
  <sensor type="perspective"><float name="fov" value="50"/><ref id="fog"/>
    <transform name="{to_world}"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film></sensor>
</scene>"""


def test_old_homogeneous_medium_by_absorption_and_scattering():
    """Mitsuba 0.x's homogeneous medium given as sigmaA / sigmaS (Mitsuba 3.9.1 calls them unreferenced; lajolla's
    volpath tests are written so) is Mitsuba 3's sigma_t = sigma_a + sigma_s, albedo = sigma_s / sigma_t, with 0.x's
    scale multiplying both: the very image of that medium written in Mitsuba 3's names (same seed), and one that
    differs from Mitsuba's default medium (what leaving the old names out would give)."""
    old = ('<rgb name="sigmaA" value="0.2, 0.5, 0.3"/><rgb name="sigmaS" value="0.6, 0, 0.1"/>'
           '<float name="scale" value="1.5"/>')
    new = ('<rgb name="sigma_t" value="0.8, 0.5, 0.4"/><rgb name="albedo" value="0.75, 0, 0.25"/>'
           '<float name="scale" value="1.5"/>')
    a = create(parse_string(MEDIUM_SCENE.format(version="0.5.0", max_depth="maxDepth", to_world="toWorld",
                                                medium=old), "old.xml"))
    b = create(parse_string(MEDIUM_SCENE.format(version="3.0.0", max_depth="max_depth", to_world="to_world",
                                                medium=new), "new.xml"))
    m = a.shapes[0].exterior
    np.testing.assert_allclose(m.sigma_t, [1.2, 0.75, 0.6])
    np.testing.assert_allclose(m.albedo, [0.75, 0, 0.25])
    ia, ib = (clrender.render(s, spp=4, seed=3).image for s in (a, b))
    assert ia.mean() > 0.05 and np.array_equal(ia, ib)
    default = create(parse_string(MEDIUM_SCENE.format(version="3.0.0", max_depth="max_depth", to_world="to_world",
                                                      medium=""), "new.xml"))
    assert not np.allclose(clrender.render(default, spp=4, seed=3).image, ib, rtol=0.05)
    # a channel with nothing in it: albedo 0 there (no 0 / 0)
    c = create(parse_string(MEDIUM_SCENE.format(version="0.6", max_depth="maxDepth", to_world="toWorld", medium=(
        '<rgb name="sigmaA" value="0, 1, 0"/><rgb name="sigmaS" value="0, 1, 2"/>')), "old.xml"))
    np.testing.assert_allclose(c.shapes[0].exterior.albedo, [0, 0.5, 1])


def test_old_homogeneous_medium_errors_are_located():
    def bad(medium, *fragments):
        with pytest.raises(SceneError) as e:
            create(parse_string(MEDIUM_SCENE.format(version="0.5.0", max_depth="maxDepth", to_world="toWorld",
                                                    medium="\n" + medium), "old.xml"))
        assert e.value.location.file == "old.xml" and e.value.location.line == 4, str(e.value)
        for f in fragments:
            assert f in str(e.value), str(e.value)
    bad('<rgb name="sigmaA" value="0.2"/>', "sigma_a needs sigma_s")
    bad('<rgb name="sigmaS" value="0.2"/><float name="sigmaT" value="1"/>', "sigma_a")
    bad('<rgb name="sigmaA" value="0.2"/><rgb name="sigmaS" value="0.2"/><float name="albedo" value="1"/>',
        "'albedo' given together")
    bad('<rgb name="sigmaA" value="0.2, -1, 0"/><rgb name="sigmaS" value="0.2"/>', "sigma_a must be non-negative")


HETERO_SCENE = """<scene version="{version}">
  <integrator type="volpath"><integer name="{max_depth}" value="3"/></integrator>
  <medium type="heterogeneous" id="smoke">{medium}<phase type="isotropic"/></medium>
  <shape type="cube"><transform name="{to_world}"><scale x="0.5" y="0.5" z="0.25"/></transform>{bsdf}
    <ref name="interior" id="smoke"/></shape>
  <shape type="sphere"><point name="center" x="0" y="-2" z="1"/><float name="radius" value="0.8"/>
    <emitter type="area"><rgb name="radiance" value="8"/></emitter></shape>
  <sensor type="perspective"><float name="fov" value="45"/>
    <transform name="{to_world}"><lookat origin="0, 0.5, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film></sensor>
</scene>"""


def test_old_heterogeneous_medium_by_density(tmp_path):
    """Mitsuba 0.6's heterogeneous medium (lajolla's hetvol tests): its `density` gridvolume is the extinction
    (times `scale`), spanning the bounding box its file gives (0.6 knew no unit cube), and `method`/`stepSize`
    only say how to sample it, and the medium's box without a BSDF is an index-matched boundary (0.6's
    Shape::configure; Mitsuba 3.9.1 would make it diffuse and hide the medium): the very image of the same medium in
    Mitsuba 3's names with a null BSDF (same seed); without the bounding box (the grid on the unit cube, Mitsuba 3's
    default), or with Mitsuba 3's diffuse box, it differs."""
    from clrender.volumes.gridvolume import write_vol

    z, y, x = np.mgrid[0:6, 0:8, 0:8] / 7.0
    write_vol(tmp_path / "d.vol", 0.2 + x * y + z, bbox=(-0.5, -0.5, -0.25, 0.5, 0.5, 0.25))
    old = ('<string name="method" value="woodcock"/><float name="stepSize" value="0.1"/>'
           '<volume name="density" type="gridvolume"><string name="filename" value="d.vol"/></volume>'
           '<volume name="albedo" type="constvolume"><rgb name="value" value="0.8"/></volume>'
           '<float name="scale" value="4"/>')
    new = ('<volume name="sigma_t" type="gridvolume"><string name="filename" value="d.vol"/>'
           '<boolean name="use_grid_bbox" value="true"/></volume>'
           '<volume name="albedo" type="constvolume"><rgb name="value" value="0.8"/></volume>'
           '<float name="scale" value="4"/>')
    scenes = []
    null = '<bsdf type="null"/>'
    for version, md, tw, medium, bsdf in (("0.5.0", "maxDepth", "toWorld", old, ""),
                                          ("3.0.0", "max_depth", "to_world", new, null),
                                          ("3.0.0", "max_depth", "to_world", new.replace("true", "false"), null),
                                          ("3.0.0", "max_depth", "to_world", new, "")):
        path = tmp_path / f"s{len(scenes)}.xml"
        path.write_text(HETERO_SCENE.format(version=version, max_depth=md, to_world=tw, medium=medium, bsdf=bsdf))
        scenes.append(clrender.load_scene(path))
    a, b, unit, diffuse = (clrender.render(s, spp=4, seed=3).image for s in scenes)
    assert a.mean() > 0.01 and np.array_equal(a, b)
    assert not np.allclose(unit, b, rtol=0.05) and not np.allclose(diffuse, b, rtol=0.05)
    path = tmp_path / "bad.xml"
    path.write_text(HETERO_SCENE.format(version="0.5.0", max_depth="maxDepth", to_world="toWorld", bsdf="", medium=old.replace(
        "</volume>", '</volume>\n<volume name="orientation" type="constvolume"><vector name="value" x="0" y="0" '
        'z="1"/></volume>', 1)))
    with pytest.raises(SceneError, match="micro-flake") as e:
        clrender.load_scene(path)
    assert e.value.location.line == 4
