"""The Mitsuba 3 reader (clrender/scene/mitsuba_xml.py): format detection, defaults and -D, ids and references,
nested includes (resolved as Mitsuba 3.9 resolves them), transforms, rgb/spectrum properties (numbers checked
against Mitsuba 3.9), Mitsuba's mesh options and meshes, and every error path with its location."""
import logging
import re
import struct
import zlib

import numpy as np
import pytest

import clrender.plugins  # noqa: F401
from clrender.errors import SceneError
from clrender.scene.registry import create
from clrender.scene.xmlparser import parse_file, parse_string

HEAD = '<scene version="3.0.0">'
SENSOR = ('<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>'
          '<integer name="height" value="6"/></film></sensor>')


def load(body: str, **kw):
    """The Scene of a Mitsuba file made of `body` (and a sensor unless it has one)."""
    sensor = "" if "<sensor" in body else SENSOR
    return create(parse_string(f"{HEAD}{sensor}{body}</scene>", "m.xml", **kw))


def err(text: str, line: int | None = None, col: int | None = None, *fragments: str, **kw) -> SceneError:
    """The SceneError of loading `text` as m.xml; when given, checked to be at `line` (and `col`) and to say
    `fragments`."""
    with pytest.raises(SceneError) as e:
        create(parse_string(text, "m.xml", **kw))
    if line is not None:
        at(e.value, line, col)
    for fragment in fragments:
        assert fragment in str(e.value), str(e.value)
    return e.value


def at(e: SceneError, line: int, col: int | None = None, file: str = "m.xml") -> None:
    assert e.location is not None, str(e)
    assert (e.location.file, e.location.line) == (file, line), str(e)
    if col is not None:
        assert e.location.col == col, str(e)


# ------------------------------------------------------------------------------------------------ detection
def test_version_attribute_selects_the_mitsuba_reader():
    assert parse_string(f"{HEAD}</scene>").format == "mitsuba"
    assert parse_string('<scene version="2.1"></scene>').format == "mitsuba"
    assert parse_string("<scene></scene>").format == "nori"


def test_unsupported_version_is_located():
    err('<scene\n version="4.0.0"></scene>', 2, 2, "'version'", "4.0.0", "Mitsuba 3 reader")
    e = err('<scene version="three"></scene>')
    assert "major.minor" in str(e)


def test_load_scene_detects_the_format(tmp_path):
    from clrender import load_scene

    (tmp_path / "s.xml").write_text(f"{HEAD}{SENSOR}<shape type='cube'/></scene>")
    scene = load_scene(tmp_path / "s.xml")
    assert (scene.width, scene.height, scene.sample_count) == (8, 6, 4)
    assert len(scene.shapes) == 1 and type(scene.integrator).__name__ in ("PathMis", "MitsubaPath")


# ------------------------------------------------------------------------------------------ defaults, -D
def test_defaults_and_defines():
    body = '<default name="w" value="0.25"/><shape type="cube"><bsdf type="diffuse"><float name="reflectance" value="$w"/></bsdf></shape>'
    assert load(body).shapes[0].bsdf.albedo.tolist() == [0.25] * 3
    assert load(body, defines={"w": "0.5"}).shapes[0].bsdf.albedo.tolist() == [0.5] * 3


@pytest.mark.parametrize("defines", [{"nope": "1"}, {"w": "0.5", "nope": "1"}, {"unused_default": "2"}])
def test_a_define_that_fills_nothing_is_an_error(defines):
    """Mitsuba 3.9.1 stops with "Found unused parameters" for a -D naming no $name the file uses, even one a
    <default> declares."""
    body = ('<default name="w" value="0.25"/><default name="unused_default" value="1"/>'
            '<shape type="cube"><bsdf type="diffuse"><float name="reflectance" value="$w"/></bsdf></shape>')
    unused = [k for k in defines if k != "w"]
    with pytest.raises(SceneError) as e:
        load(body, defines=defines)
    assert e.value.location.file == "m.xml" and "-D " + unused[0] + "=" in str(e.value) and "uses $w" in str(e.value)
    assert load(body, defines={"w": "0.5"}).shapes[0].bsdf.albedo.tolist() == [0.5] * 3


def test_undefined_variable_is_located():
    err(f'{HEAD}\n<shape type="cube"><bsdf type="diffuse"><float name="reflectance" value="$nope"/></bsdf></shape></scene>',
        2, None, "$nope", "-D nope=")


def test_default_given_twice():
    err(f'{HEAD}<default name="a" value="1"/>\n<default name="a" value="2"/></scene>', 2, 1, "given twice")


# ------------------------------------------------------------------------------------------------ ids, refs
def test_reference_shares_one_object():
    scene = load('<bsdf type="diffuse" id="w"><rgb name="reflectance" value="0.1, 0.2, 0.3"/></bsdf>'
                 '<shape type="cube"><ref id="w"/></shape><shape type="cube"><ref name="bsdf" id="w"/></shape>')
    a, b = scene.shapes[0].bsdf, scene.shapes[1].bsdf
    assert a is b and a.albedo.tolist() == [0.1, 0.2, 0.3]


def test_alias_names_the_same_object():
    scene = load('<bsdf type="diffuse" id="w"/><alias id="w" as="white"/><shape type="cube"><ref id="white"/></shape>')
    assert scene.shapes[0].bsdf.albedo.tolist() == [0.5] * 3


def test_reference_to_unknown_id_is_located():
    err(f'{HEAD}<bsdf type="diffuse" id="w"/>\n<shape type="cube">  <ref id="white"/></shape></scene>',
        2, 31, "unknown id 'white'", "no object in the scene", "declared: w")


def test_reference_to_an_object_declared_later():
    """Mitsuba 3.9.1 resolves refs once the whole file is read (its own Cornell boxes refer to BSDFs declared after
    the shapes): the later object, shared, and a named ref renames a texture as a ref before it does."""
    scene = load('<shape type="cube"><ref id="w"/></shape><shape type="cube"><ref name="bsdf" id="w"/></shape>'
                 '<shape type="cube"><bsdf type="diffuse"><ref name="reflectance" id="t"/></bsdf></shape>'
                 '<bsdf type="diffuse" id="w"><rgb name="reflectance" value="0.1, 0.2, 0.3"/></bsdf>'
                 '<texture type="checkerboard" id="t"><rgb name="color0" value="0.25"/></texture>')
    a, b, c = (s.bsdf for s in scene.shapes)
    assert a is b and a.albedo.tolist() == [0.1, 0.2, 0.3]
    assert c.texture is not None and c.texture.spec.type == "checkerboard" and c.texture.spec.name == "reflectance"


def test_an_unused_declaration_of_a_type_clrender_lacks_is_left_out(tmp_path, caplog):
    """Mitsuba 3 builds every top-level declaration and renders a scene as if an unused one were not there (the
    Mitsuba tutorials' lego scene declares a diffuse BSDF with a `volume` texture that no shape uses): clrender
    leaves such a one out with a warning at its line; referenced, the type it lacks is the located error, and so is
    a type that Mitsuba does not have either, used or not."""
    from clrender import load_scene

    unused = ('<bsdf type="diffuse" id="grid">\n<texture type="volume" name="reflectance">'
              '<volume type="constvolume" name="volume"><rgb name="value" value="0.2"/></volume></texture></bsdf>\n'
              '<phase type="rayleigh" id="t"/>\n')
    (tmp_path / "s.xml").write_text(f'{HEAD}{SENSOR}\n{unused}<bsdf type="diffuse" id="w"/>'
                                    f'<shape type="cube"><ref id="w"/></shape></scene>')
    with caplog.at_level(logging.WARNING, logger="clrender"):
        scene = load_scene(tmp_path / "s.xml")
    assert len(scene.shapes) == 1 and scene.shapes[0].bsdf.albedo.tolist() == [0.5] * 3
    assert 's.xml:2:1: <bsdf type="diffuse"> holds <texture type="volume">' in caplog.text
    assert 's.xml:4:1: <phase type="rayleigh"> is a type clrender lacks' in caplog.text
    (tmp_path / "s.xml").write_text(f'{HEAD}{SENSOR}\n{unused}<shape type="cube"><ref id="grid"/></shape></scene>')
    with pytest.raises(SceneError) as e:
        load_scene(tmp_path / "s.xml")
    assert "unknown texture type 'volume'" in str(e.value) and e.value.location.line == 3
    (tmp_path / "s.xml").write_text(f'{HEAD}{SENSOR}\n<texture type="no_such_texture" id="t"/>'
                                    f'<shape type="cube"/></scene>')
    with pytest.raises(SceneError, match="unknown texture type 'no_such_texture'") as e:
        load_scene(tmp_path / "s.xml")
    assert e.value.location.line == 2


@pytest.mark.parametrize("refs, expected", [('<ref id="s"/><ref id="f"/>', (7, 5, 3, "box")),
                                             ("", (4, 768, 576, "gaussian"))])
def test_sampler_film_and_rfilter_declared_at_the_top_level(refs, expected):
    """Mitsuba's documentation scenes declare `<sampler id>` in the main file for a sensor in an included file to
    refer to. A sensor's <ref>s take them (Mitsuba 3.9.1: 7 spp, 5 x 3); unreferenced, Mitsuba ignores them and so
    do we (its defaults: 4 spp, 768 x 576, gaussian)."""
    scene = load('<sampler type="independent" id="s"><integer name="sample_count" value="7"/></sampler>'
                 '<film type="hdrfilm" id="f"><integer name="width" value="5"/><integer name="height" value="3"/>'
                 '<ref id="r"/></film><rfilter type="box" id="r"/>'
                 f'<sensor type="perspective">{refs}</sensor><shape type="sphere"/>')
    from clrender.filters.box import BoxFilter
    from clrender.filters.gaussian import GaussianFilter
    kind = {BoxFilter: "box", GaussianFilter: "gaussian"}[next(c for c in type(scene.camera.filter).__mro__
                                                               if c in (BoxFilter, GaussianFilter))]
    assert (scene.sample_count, scene.width, scene.height, kind) == expected


def test_alias_of_a_later_id_is_refused_as_in_mitsuba():
    err(f'{HEAD}\n<alias id="w" as="x"/><bsdf type="diffuse" id="w"/></scene>', 2, 12, "<alias> of unknown id 'w'")


def test_circular_reference_is_located_at_the_ref_closing_it():
    """Only a ref to a later id can close a cycle; Mitsuba 3.9.1 refuses it ("circular reference detected")."""
    err(f'{HEAD}{SENSOR}<bsdf type="twosided" id="a"><ref id="b"/></bsdf>\n<bsdf type="twosided" id="b">'
        f'<ref id="a"/></bsdf><shape type="cube"><ref id="a"/></shape></scene>', 2, 30, "circular reference",
        "a -> b -> a")


def test_reference_to_a_bsdf_where_a_texture_belongs_is_located_at_the_ref():
    e = err(f'{HEAD}{SENSOR}<bsdf type="diffuse" id="b"/>\n<shape type="cube"><bsdf type="diffuse">\n'
            f'   <ref name="reflectance" id="b"/></bsdf></shape></scene>', 3, 4,
            "parameter 'reflectance'", "gets 'b', a <bsdf type=\"diffuse\">", "accepts <texture> only")
    assert "declared at m.xml:1:" in str(e)


def test_id_declared_twice_is_located():
    err(f'{HEAD}<bsdf type="diffuse" id="w"/>\n<bsdf type="diffuse" id="w"/></scene>', 2, 26, "declared twice")


# ------------------------------------------------------------------------------------------------ includes
def write(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


CUBE_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


def test_nested_includes_resolve_as_mitsuba(tmp_path, monkeypatch):
    """Checked against Mitsuba 3.9: an include is found next to the file that includes it (or the main file);
    a mesh named in an included file is found next to the main file (or the current directory), not next to
    the included file."""
    write(tmp_path / "main.xml", f'{HEAD}{SENSOR}<include filename="sub/a.xml"/></scene>')
    write(tmp_path / "sub" / "a.xml", f'{HEAD}<include filename="deeper/b.xml"/></scene>')
    write(tmp_path / "sub" / "deeper" / "b.xml",
          f'{HEAD}<shape type="obj"><string name="filename" value="tri.obj"/></shape></scene>')
    write(tmp_path / "tri.obj", CUBE_OBJ)
    write(tmp_path / "sub" / "deeper" / "tri.obj", CUBE_OBJ)
    monkeypatch.chdir(tmp_path / "sub")
    spec = parse_file(tmp_path / "main.xml")
    (shape,) = spec.children_with_tag("shape")
    assert shape.props.get_string("filename") == str(tmp_path / "tri.obj")
    assert shape.location.file == str(tmp_path / "sub" / "deeper" / "b.xml")


def mesh_files(spec) -> list[str]:
    return [s.props.get_string("filename") for s in spec.walk() if s.props.has("filename")]


def test_path_folders_resolve_as_mitsuba(tmp_path, monkeypatch):
    """Which file wins, as Mitsuba 3.9.1 loads these very layouts (a triangle of a different size in each folder,
    its bounding box printed): the last <path> first, then the earlier ones, then the main file's folder; a
    <path> written after the shape counts too (files are resolved when the plugins are built); a <path> in an
    included file serves only the includes below it; a nested include is looked for beside the file including it
    before the main file's folder."""
    for d in ("A", "B", "C", ".", "sub/D"):
        write(tmp_path / d / "m.obj", CUBE_OBJ)
    monkeypatch.chdir(tmp_path / "C")
    two = write(tmp_path / "two.xml", f'{HEAD}{SENSOR}<path value="A"/><path value="B"/>'
                                      '<shape type="obj"><string name="filename" value="m.obj"/></shape></scene>')
    assert mesh_files(parse_file(two)) == [str(tmp_path / "B" / "m.obj")]
    after = write(tmp_path / "after.xml", f'{HEAD}{SENSOR}<shape type="obj"><string name="filename" value="m.obj"/>'
                                          '</shape><path value="A"/></scene>')
    assert mesh_files(parse_file(after)) == [str(tmp_path / "A" / "m.obj")]
    write(tmp_path / "sub" / "mid.xml", f'{HEAD}<path value="D"/><include filename="leaf.xml"/></scene>')
    write(tmp_path / "sub" / "D" / "leaf.xml",
          f'{HEAD}<shape type="obj"><string name="filename" value="m.obj"/></shape></scene>')
    scoped = write(tmp_path / "scoped.xml", f'{HEAD}{SENSOR}<include filename="sub/mid.xml"/></scene>')
    assert mesh_files(parse_file(scoped)) == [str(tmp_path / "m.obj")]
    write(tmp_path / "inc.xml", f'{HEAD}<shape type="obj"><string name="filename" value="A/m.obj"/></shape></scene>')
    write(tmp_path / "sub" / "inc.xml",
          f'{HEAD}<shape type="obj"><string name="filename" value="B/m.obj"/></shape></scene>')
    write(tmp_path / "sub" / "outer.xml", f'{HEAD}<include filename="inc.xml"/></scene>')
    nearest = write(tmp_path / "nearest.xml", f'{HEAD}{SENSOR}<include filename="sub/outer.xml"/></scene>')
    assert mesh_files(parse_file(nearest)) == [str(tmp_path / "B" / "m.obj")]


def test_path_errors_are_located(tmp_path):
    write(tmp_path / "s.xml", f'{HEAD}\n  <path value="nowhere"/></scene>')
    with pytest.raises(SceneError) as e:
        parse_file(tmp_path / "s.xml")
    at(e.value, 2, 16, file=str(tmp_path / "s.xml"))
    assert "folder 'nowhere' not found" in str(e.value)
    err(f'{HEAD}<shape type="cube">\n<path value="."/></shape></scene>', 2, 1, "only allowed directly inside")


def test_mesh_next_to_an_included_file_only_is_missing(tmp_path, monkeypatch):
    from clrender import load_scene

    write(tmp_path / "main.xml", f'{HEAD}{SENSOR}<include filename="sub/a.xml"/></scene>')
    write(tmp_path / "sub" / "a.xml", f'{HEAD}\n<shape type="obj"><string name="filename" value="tri.obj"/></shape></scene>')
    write(tmp_path / "sub" / "tri.obj", CUBE_OBJ)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SceneError) as e:
        load_scene(tmp_path / "main.xml")
    at(e.value, 2, file=str(tmp_path / "sub" / "a.xml"))
    assert str(tmp_path / "tri.obj") in str(e.value) and "Mitsuba 3 reader" in str(e.value)


def test_missing_include_is_located(tmp_path):
    write(tmp_path / "main.xml", f'{HEAD}\n  <include filename="nowhere.xml"/></scene>')
    with pytest.raises(SceneError) as e:
        parse_file(tmp_path / "main.xml")
    at(e.value, 2, 22, file=str(tmp_path / "main.xml"))
    assert "cannot include 'nowhere.xml'" in str(e.value) and "looked in" in str(e.value)


def test_included_default_for_a_name_already_given_is_ignored(tmp_path):
    """Mitsuba 3.9.1 keeps the first <default> of a name and passes over later ones (its own participating-media test
    scenes give `spp` in the file and again in the preamble they include); in one file a second one stays an error."""
    write(tmp_path / "pre.xml", f'{HEAD}<default name="r" value="0.9"/><default name="g" value="0.3"/></scene>')
    write(tmp_path / "main.xml", f'{HEAD}<default name="r" value="0.2"/><include filename="pre.xml"/>{SENSOR}'
                                 '<shape type="cube"><bsdf type="diffuse"><rgb name="reflectance" value="$r, $g, 0"/>'
                                 '</bsdf></shape></scene>')
    scene = create(parse_file(tmp_path / "main.xml"))
    assert scene.shapes[0].bsdf.albedo.tolist() == [0.2, 0.3, 0.0]


def test_include_cycle_is_an_error(tmp_path):
    write(tmp_path / "main.xml", f'{HEAD}<include filename="a.xml"/></scene>')
    write(tmp_path / "a.xml", f'{HEAD}\n<include filename="a.xml"/></scene>')
    with pytest.raises(SceneError) as e:
        parse_file(tmp_path / "main.xml")
    at(e.value, 2, file=str(tmp_path / "a.xml"))
    assert "includes itself" in str(e.value)


@pytest.mark.parametrize("depth, ok", [(14, True), (15, False), (200, False)])
def test_include_depth_is_limited_as_in_mitsuba(tmp_path, depth, ok):
    """Mitsuba 3.9.1 reads a chain of 14 nested includes and refuses the 15th ("Exceeded maximum include recursion
    depth of 15"); a long chain without a cycle is no cycle."""
    write(tmp_path / "main.xml", f'{HEAD}{SENSOR}<include filename="i1.xml"/></scene>')
    for i in range(1, depth):
        write(tmp_path / f"i{i}.xml", f'{HEAD}\n<include filename="i{i + 1}.xml"/></scene>')
    write(tmp_path / f"i{depth}.xml", f'{HEAD}<shape type="cube"/></scene>')
    if ok:
        assert len(parse_file(tmp_path / "main.xml").children_with_tag("shape")) == 1
        return
    with pytest.raises(SceneError) as e:
        parse_file(tmp_path / "main.xml")
    at(e.value, 2, file=str(tmp_path / "i14.xml"))
    assert "maximum include depth, 15" in str(e.value) and "itself" not in str(e.value)


def test_error_inside_an_include_names_that_file(tmp_path):
    write(tmp_path / "main.xml", f'{HEAD}<include filename="a.xml"/></scene>')
    write(tmp_path / "a.xml", f'{HEAD}\n\n<shape type="cube"><float name="x" value="1,5"/></shape></scene>')
    with pytest.raises(SceneError) as e:
        parse_file(tmp_path / "main.xml")
    at(e.value, 3, file=str(tmp_path / "a.xml"))


# ---------------------------------------------------------------------------------------------- transforms
def shape_to_world(ops: str) -> np.ndarray:
    """The to_world matrix of a shape (a sensor would refuse these scaled chains, as Mitsuba's does)."""
    spec = parse_string(f'{HEAD}<shape type="cube"><transform name="to_world">{ops}</transform></shape></scene>')
    return spec.children[0].props.get_transform("to_world").matrix


def test_transform_chain_as_mitsuba():
    # Mitsuba 3.9: the same chain's matrix (ScalarTransform4f ops composed as its parser composes them)
    m = shape_to_world('<translate x="1"/><rotate x="1" y="1" angle="30"/><scale value="2"/>'
                       '<lookat origin="1,2,3" target="0,0,0" up="0,1,0"/>')
    expected = [[-1.675397, -0.859522, -1.242562, -0.675397], [0.760981, 1.155786, -1.770974, 2.760981],
                [1.298364, -1.731236, -0.565410, 4.298364], [0, 0, 0, 1]]
    assert np.allclose(m, expected, atol=2e-6)


def test_rotate_axis_is_not_normalised():
    m = shape_to_world('<rotate value="0, 2, 0" angle="90"/>')
    assert np.allclose(m[:3, :3], [[0, 0, 2], [0, 4, 0], [-2, 0, 0]], atol=1e-12)


def test_matrix_and_scale_forms():
    spec = parse_string(f'{HEAD}<shape type="cube"><transform name="to_world"><matrix value="1 0 0 5  0 1 0 6  0 0 1 7  0 0 0 1"/>'
                        f'<scale x="2"/></transform></shape></scene>')
    m = spec.children[0].props.get_transform("to_world").matrix
    assert np.allclose(m, [[2, 0, 0, 10], [0, 1, 0, 6], [0, 0, 1, 7], [0, 0, 0, 1]])


def test_transform_op_errors_are_located():
    err(f'{HEAD}<shape type="cube"><transform name="to_world">\n<rotate y="1"/></transform></shape></scene>',
        2, 1, "'angle'")
    err(f'{HEAD}<shape type="cube"><transform name="to_world">\n<translate value="1" y="2"/></transform></shape></scene>',
        2, None, "either 'value' or 'x', 'y', 'z'")
    err(f'{HEAD}<shape type="cube"><transform name="to_world">\n<shear value="1"/></transform></shape></scene>',
        2, 1, "<shear> is not allowed")


# Mitsuba 3.9.1's sensor to_world for a <lookat> without up (it picks coordinate_system(direction)'s first vector),
# printed from sensors()[0].world_transform()
@pytest.mark.parametrize("origin, target, matrix", [
    ("1, 2, 3", "0, 0.5, -1", [[-0.040761, 0.972826, -0.227921, 1], [0.938859, -0.040761, -0.341882, 2],
                               [-0.341882, -0.227921, -0.911685, 3]]),
    ("0, 0, 0", "0, 0, -1", [[0, 1, 0, 0], [1, 0, 0, 0], [0, 0, -1, 0]]),
    ("0, 1, 0", "0, -2, 0", [[0, 1, 0, 0], [0, 0, -1, 1], [-1, 0, 0, 0]]),
])
def test_lookat_without_up_as_mitsuba(origin, target, matrix):
    for up in ("", ' up="0, 0, 0"'):
        scene = load(f'<sensor type="perspective"><transform name="to_world"><lookat origin="{origin}" '
                     f'target="{target}"{up}/></transform></sensor><shape type="cube"/>')
        assert np.allclose(scene.camera.to_world.matrix[:3], matrix, atol=1e-6)


# ---------------------------------------------------------------------------------------------- properties
SPECTRUM = "400:0.1, 500:0.8, 600:0.3, 700:0.2"


def test_colour_forms():
    body = ''.join(f'<shape type="cube"><bsdf type="diffuse">{p}</bsdf></shape>' for p in (
        '<rgb name="reflectance" value="0.3"/>', '<float name="reflectance" value="0.2"/>',
        '<spectrum name="reflectance" value="0.4"/>', f'<spectrum name="reflectance" value="{SPECTRUM}"/>'))
    got = [s.bsdf.albedo for s in load(body).shapes]
    assert got[0].tolist() == [0.3] * 3 and got[1].tolist() == [0.2] * 3 and got[2].tolist() == [0.4] * 3
    # Mitsuba 3.9 llvm_ad_rgb/scalar_rgb: the reflectance this spectrum becomes (D65-lit, bounded)
    assert np.allclose(got[3], [0.137488, 0.624922, 0.470022], atol=2e-6)


def test_spectrum_in_an_emitter_uses_mitsubas_emitter_convention():
    scene = load(f'<shape type="cube"><emitter type="area"><spectrum name="radiance" value="{SPECTRUM}"/></emitter></shape>'
                 '<shape type="cube"><emitter type="area"><spectrum name="radiance" value="2"/></emitter></shape>')
    # Mitsuba 3.9's numbers: an emitter's spectrum is equal-energy based (no D65); a constant is
    # value * xyz_to_srgb(1, 1, 1)
    assert np.allclose(scene.shapes[0].emitter.radiance, [0.211765, 0.591459, 0.416992], atol=2e-6)
    assert np.allclose(scene.shapes[1].emitter.radiance, [2.40959, 1.89658, 1.81783], atol=2e-5)


def test_spectrum_conversion_matches_mitsuba_more_widely():
    from clrender.scene.spectrum import spectrum_to_rgb

    # (spectrum, Mitsuba 3.9's reflectance RGB, its emitter RGB)
    for text, refl, emit in [
        ("400:0.5, 700:0.5", [0.497671, 0.499878, 0.497455], [0.599847, 0.47476, 0.451722]),
        ("360:1, 830:1", [0.998985, 0.998874, 0.998802], [1.20488, 0.948228, 0.909267]),
        ("450:0.2, 550:0.1", [0, 0.0873444, 0.106762], [0, 0.0811989, 0.0910114]),
    ]:
        lam, val = zip(*[map(float, p.split(":")) for p in text.split(", ")])
        assert np.allclose(spectrum_to_rgb(lam, val, warn=False), refl, atol=2e-5), text
        assert np.allclose(spectrum_to_rgb(lam, val, emitter=True, warn=False), emit, atol=2e-5), text


def test_out_of_gamut_spectrum_warns(caplog):
    with caplog.at_level(logging.WARNING, logger="clrender"):
        load('<shape type="cube"><bsdf type="diffuse"><spectrum name="reflectance" value="450:0.2, 550:0.1"/></bsdf></shape>')
    assert "outside the sRGB gamut" in caplog.text


@pytest.mark.parametrize("value, message", [
    ("400:0.1, 300:0.2", "increase"),
    ("400:0.1", "at least two"),
    ("400:0.1, 500", "bad wavelength:value pair '500'"),
    ("0.1 0.2 0.3", "neither one constant"),
    ("400:x, 500:1", "bad wavelength:value pair '400:x'"),
])
def test_unsupported_spectrum_is_located(value, message):
    err(f'{HEAD}<shape type="cube"><bsdf type="diffuse">\n  <spectrum name="reflectance" value="{value}"/></bsdf></shape></scene>',
        2, 39, message)


def test_spectrum_file_is_refused():
    err(f'{HEAD}<shape type="cube"><bsdf type="diffuse">\n<spectrum name="reflectance" filename="a.spd"/></bsdf></shape></scene>',
        2, 1, "not supported")


def test_point_written_as_xyz():
    spec = parse_string(f'{HEAD}<emitter type="x"><point name="position" x="1" z="3"/></emitter></scene>')
    assert spec.children[0].props.get_point("position").tolist() == [1, 0, 3]


def test_bad_number_is_located():
    err(f'{HEAD}<shape type="cube">\n   <float name="a" value="1.5.2"/></shape></scene>',
        2, 27, "bad number '1.5.2'", "Mitsuba 3 reader")
    err(f'{HEAD}<shape type="cube">\n<integer name="a" value="2.5"/></shape></scene>', 2, None, "bad integer")
    err(f'{HEAD}<shape type="cube">\n<boolean name="a" value="yes"/></shape></scene>', 2, None, "bad boolean")
    err(f'{HEAD}<shape type="cube">\n<rgb name="a" value="1, 2"/></shape></scene>', 2, None, "needs 3 or 1 numbers")


# ------------------------------------------------------------------------------------- unknown things
def test_unknown_plugin_names_the_known_ones():
    e = err(f'{HEAD}{SENSOR}\n  <shape type="teapot"/></scene>', 2, 3, "unknown shape type 'teapot'", "Mitsuba 3")
    assert re.search(r"known: .*cube.*obj.*ply.*serialized", str(e))


def test_unknown_parameter_names_the_supported_ones(tmp_path):
    from clrender import load_scene

    write(tmp_path / "s.xml", f'{HEAD}{SENSOR}<shape type="cube"><bsdf type="diffuse">\n'
                              f'<rgb name="reflectanse" value="0.5"/></bsdf></shape></scene>')
    with pytest.raises(SceneError) as e:
        load_scene(tmp_path / "s.xml")
    at(e.value, 2, 1, file=str(tmp_path / "s.xml"))
    msg = str(e.value)
    assert "'reflectanse' is not used by <bsdf type=\"diffuse\">; it takes reflectance" in msg
    assert "[Mitsuba 3 reader]" in msg


def test_unknown_tag_is_located():
    err(f'{HEAD}\n<mesh type="obj"/></scene>', 2, 1, "unknown tag <mesh>", "<shape>")


def test_wrong_property_kind():
    err(f'{HEAD}{SENSOR}<shape type="cube"><bsdf type="diffuse">\n<string name="reflectance" value="red"/></bsdf></shape></scene>',
        2, None, "expects a <rgb>")


def test_scene_without_sensor_is_an_error():
    e = err(f'{HEAD}<shape type="cube"/></scene>')
    assert "no sensor" in str(e)


def test_stratifying_samplers_use_scrambled_sobol(caplog):
    from clrender.pack import pack_scene
    from clrender.renderer import render_defines

    for kind in ("stratified", "multijitter", "orthogonal", "ldsampler", "sobol", "halton", "hammersley"):
        with caplog.at_level(logging.INFO, logger="clrender"):
            scene = load(f'<sensor type="perspective"><sampler type="{kind}"><integer name="sample_count" '
                         'value="16"/></sampler><film type="hdrfilm"/></sensor><shape type="cube"/>')
        assert scene.sample_count == 16 and "scrambled Sobol" in caplog.text
        buffers = pack_scene(scene)
        assert buffers.sampler == "sobol" and render_defines(scene, buffers)["CLR_SAMPLER_SOBOL"] == 1
    plain = load('<shape type="cube"/>')
    assert "CLR_SAMPLER_SOBOL" not in render_defines(plain, pack_scene(plain))


# ---------------------------------------------------------------------------------------------- meshes
def test_smooth_normals_as_mitsuba(tmp_path):
    """Mitsuba 3.9's vertex normals for this OBJ without normals (angle-weighted), and its flipped uvs."""
    write(tmp_path / "q.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
    scene = load(f'<shape type="obj"><string name="filename" value="{tmp_path / "q.obj"}"/></shape>'
                 f'<shape type="obj"><string name="filename" value="{tmp_path / "q.obj"}"/>'
                 '<boolean name="face_normals" value="true"/><boolean name="flip_tex_coords" value="false"/></shape>')
    smooth, flat = scene.shapes[0].mesh, scene.shapes[1].mesh
    assert np.allclose(smooth.normals, [[0.3705, -0.3705, 0.8518], [0, 0, 1], [0.3705, -0.3705, 0.8518],
                                        [0.5774, -0.5774, 0.5774]], atol=1e-4)
    assert smooth.uvs.tolist() == [[0, 1], [1, 1], [1, 0], [0, 0]]
    assert flat.normals is None and flat.uvs.tolist() == [[0, 0], [1, 0], [1, 1], [0, 1]]


def test_flip_normals_turns_the_surface():
    a, b = (load(f'<shape type="cube"><boolean name="flip_normals" value="{v}"/></shape>').shapes[0].mesh
            for v in ("false", "true"))
    assert np.allclose(a.face_normals(), -b.face_normals()) and np.allclose(a.normals, -b.normals)


def test_cube_is_mitsubas():
    from clrender.shapes.cube import cube_mesh

    m = cube_mesh()
    # rows 0, 5, 13 and 22 of Mitsuba 3.9's cube (position, normal, uv), and its first and last faces
    for i, p, n, uv in [(0, (1, -1, -1), (0, -1, 0), (0, 1)), (5, (-1, 1, -1), (0, 1, 0), (1, 1)),
                        (13, (1, 1, 1), (0, 0, 1), (1, 1)), (22, (-1, -1, -1), (0, 0, -1), (1, 0))]:
        assert (m.positions[i].tolist(), m.normals[i].tolist(), m.uvs[i].tolist()) == (list(p), list(n), list(uv))
    assert m.faces[0].tolist() == [0, 1, 2] and m.faces[-1].tolist() == [23, 20, 22]
    assert np.allclose(np.einsum("ij,ij->i", m.face_normals(), m.normals[m.faces[:, 0]]), 1)   # outward winding


def test_serialized_round_trip_and_shape_index(tmp_path):
    from clrender.shapes.cube import cube_mesh
    from clrender.shapes.meshdata import MeshData
    from clrender.shapes.serializedfile import load_serialized, write_serialized

    tri = MeshData(positions=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], normals=None, uvs=[[0, 0], [1, 0], [0, 1]],
                   faces=[[0, 1, 2]])
    for version in (3, 4):
        for double in (False, True):
            path = tmp_path / f"m{version}{double}.serialized"
            write_serialized(path, [("cube", cube_mesh()), ("tri", tri)], version=version, double=double)
            a, b = load_serialized(path, None, 0), load_serialized(path, None, 1)
            assert np.array_equal(a.positions, cube_mesh().positions) and np.array_equal(a.faces, cube_mesh().faces)
            assert np.array_equal(a.normals, cube_mesh().normals) and b.normals is None
            assert b.uvs.tolist() == [[0, 0], [1, 0], [0, 1]]
    scene = load(f'<shape type="serialized"><string name="filename" value="{path}"/>'
                 '<integer name="shape_index" value="1"/></shape>')
    assert len(scene.shapes[0].mesh.faces) == 1 and scene.shapes[0].mesh.normals is not None  # computed


def test_serialized_errors_are_located(tmp_path):
    from clrender import load_scene
    from clrender.shapes.cube import cube_mesh
    from clrender.shapes.serializedfile import write_serialized

    write_serialized(tmp_path / "one.serialized", [cube_mesh()])
    (tmp_path / "bad.serialized").write_bytes(struct.pack("<HH", 0x1234, 4) + zlib.compress(b"x"))
    (tmp_path / "cut.serialized").write_bytes((tmp_path / "one.serialized").read_bytes()[:40])
    (tmp_path / "lfs.serialized").write_bytes(b"version https://git-lfs.github.com/spec/v1\noid sha256:0\nsize 9\n")
    for name, index, message in [("one", 1, "shape_index 1 is out of range: the file holds 1 mesh"),
                                 ("bad", 0, "not the serialized format's 0x041C"),
                                 ("lfs", 0, "not the serialized format's 0x041C; this is a Git LFS pointer"),
                                 ("cut", 0, "corrupt|ends inside")]:
        write(tmp_path / "s.xml", f'{HEAD}{SENSOR}<shape type="serialized">\n<string name="filename" value="{name}.serialized"/>'
                                  f'<integer name="shape_index" value="{index}"/></shape></scene>')
        with pytest.raises(SceneError) as e:
            load_scene(tmp_path / "s.xml")
        at(e.value, 2, file=str(tmp_path / "s.xml"))
        assert re.search(message, str(e.value)), str(e.value)


def test_serialized_zlib_bomb_is_refused_from_its_counts(tmp_path, monkeypatch):
    """A small file whose stream would inflate to gigabytes: refused before it is inflated (the whole stream used
    to be inflated at once, exhausting the memory)."""
    import clrender.shapes.serializedfile as S

    head = struct.pack("<I", S.SINGLE) + b"bomb\0" + struct.pack("<QQ", 2**33, 2**33)
    comp = zlib.compressobj(9)
    stream = comp.compress(head) + comp.compress(bytes(1 << 24)) + comp.flush()  # 16 MiB of zeros, ~16 KiB
    (tmp_path / "bomb.serialized").write_bytes(struct.pack("<HH", S.MAGIC, 4) + stream)
    inflated = []
    real = zlib.decompressobj
    monkeypatch.setattr(S.zlib, "decompressobj", lambda: _Counting(real(), inflated))
    with pytest.raises(SceneError, match="claims 8589934592 vertices"):
        S.load_serialized(tmp_path / "bomb.serialized")
    assert sum(inflated) <= 1 << 16


class _Counting:
    def __init__(self, d, sizes):
        self.d, self.sizes = d, sizes

    def decompress(self, data, max_length=0):
        out = self.d.decompress(data, max_length)
        self.sizes.append(len(out))
        return out

    @property
    def unconsumed_tail(self):
        return self.d.unconsumed_tail


def test_crop_window_must_fit():
    err(f'{HEAD}<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="10"/>'
        f'\n<integer name="crop_width" value="11"/></film></sensor></scene>', 2, None, "does not fit")
