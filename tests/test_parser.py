"""The XML reader: a full scene's PluginSpec tree, and every error kind with its file:line:col."""
import os
import textwrap

import numpy as np
import pytest

from clrender.errors import SceneError
from clrender.scene.spec import PluginSpec
from clrender.scene.xmlparser import parse_file, parse_string

CORNELL = """\
<?xml version="1.0" encoding="utf-8"?>
<!-- a small but complete Nori scene -->
<scene>
    <integrator type="path_mis"/>
    <sampler type="independent">
        <integer name="sampleCount" value="64"/>
    </sampler>
    <camera type="perspective">
        <float name="fov" value="27.79"/>
        <transform name="toWorld">
            <scale value="-1,1,1"/>
            <lookat target="0, 0.9, 0" origin="0 0.9 4" up="0,1,0"/>
        </transform>
        <integer name="width" value="800"/>
        <integer name="height" value="600"/>
        <rfilter type="gaussian">
            <float name="radius" value="2"/>
        </rfilter>
    </camera>
    <mesh type="obj">
        <string name="filename" value="meshes/light.obj"/>
        <bsdf type="diffuse">
            <color name="albedo" value="0.725 0.71 0.68"/>
        </bsdf>
        <emitter type="area">
            <color name="radiance" value="15, 15, 15"/>
        </emitter>
    </mesh>
    <mesh type="sphere">
        <point name="center" value="0.4,0.3,0.2"/>
        <float name="radius" value="0.3"/>
        <bsdf type="dielectric"/>
        <boolean name="flag" value="TRUE"/>
    </mesh>
</scene>
"""


def err(text: str, line: int | None = None, col: int | None = None, *fragments: str, **kw) -> SceneError:
    """The SceneError of parsing `text`; when given, checked to be at `line` (and `col`) and to say `fragments`."""
    with pytest.raises(SceneError) as e:
        parse_string(text, **kw)
    if line is not None:
        at(e.value, line, col)
    for fragment in fragments:
        assert fragment in str(e.value), str(e.value)
    return e.value


def at(e: SceneError, line: int, col: int | None = None) -> None:
    assert e.location is not None, str(e)
    assert e.location.line == line, str(e)
    if col is not None:
        assert e.location.col == col, str(e)
    assert str(e).startswith(f"{e.location.file}:{line}:"), str(e)


# --- happy path ---------------------------------------------------------------------------------------
def test_full_scene_tree(tmp_path):
    path = tmp_path / "cbox.xml"
    path.write_text(CORNELL)
    root = parse_file(path)
    assert isinstance(root, PluginSpec)
    assert (root.tag, root.type, root.name) == ("scene", "scene", None)
    assert [(c.tag, c.type) for c in root.children] == [
        ("integrator", "path_mis"), ("sampler", "independent"), ("camera", "perspective"),
        ("mesh", "obj"), ("mesh", "sphere")]
    integrator, sampler, camera, light, sphere = root.children
    assert integrator.location.line == 4 and integrator.location.col == 5
    assert str(integrator.location) == f"{path}:4:5"

    assert sampler.props.get_int("sampleCount") == 64

    assert camera.props.names() == ["fov", "toWorld", "width", "height"]
    assert camera.props.get_float("fov") == pytest.approx(27.79)
    assert camera.props.get_int("width") == 800 and camera.props.get_int("height") == 600
    m = camera.props.get_transform("toWorld").matrix
    assert np.allclose(m, [[1, 0, 0, 0], [0, 1, 0, 0.9], [0, 0, -1, 4], [0, 0, 0, 1]])
    assert camera.props.location("toWorld").line == 10
    (rfilter,) = camera.children
    assert (rfilter.tag, rfilter.type) == ("rfilter", "gaussian")
    assert rfilter.props.get_float("radius") == 2.0

    # Relative filenames resolve against the XML file's folder; the raw text is kept.
    assert light.props.get_string("filename") == os.path.join(str(tmp_path), "meshes", "light.obj")
    assert light.props.raw("filename") == "meshes/light.obj"
    bsdf, emitter = light.children
    assert (bsdf.tag, bsdf.type) == ("bsdf", "diffuse")
    assert np.allclose(bsdf.props.get_color("albedo"), [0.725, 0.71, 0.68])
    assert (emitter.tag, emitter.type) == ("emitter", "area")
    assert np.array_equal(emitter.props.get_color("radiance"), [15, 15, 15])
    assert emitter.props.owner == '<emitter type="area">'

    assert np.allclose(sphere.props.get_point("center"), [0.4, 0.3, 0.2])
    assert sphere.props.get_float("radius") == 0.3
    assert sphere.props.get_bool("flag") is True
    assert [c.type for c in sphere.children] == ["dielectric"]
    assert len(sphere.children[0].props) == 0


def test_test_root_and_texture():
    root = parse_string("""<test type="chi2test">
  <integer name="testCount" value="3"/>
  <bsdf type="diffuse">
    <texture type="checkerboard_color" name="albedo">
      <point name="delta" value="0.5 0.5"/>
      <vector name="scale" value="0.25, 0.25"/>
      <color name="value1" value="0.2"/>
      <color name="value2" value="0.8 0.8 0.8"/>
    </texture>
  </bsdf>
  <scene><integrator type="ao"/></scene>
</test>""")
    assert (root.tag, root.type) == ("test", "chi2test")
    tex = root.children[0].children[0]
    assert (tex.tag, tex.type, tex.name) == ("texture", "checkerboard_color", "albedo")
    assert np.array_equal(tex.props.get_point2("delta"), [0.5, 0.5])
    assert np.array_equal(tex.props.get_vector2("scale"), [0.25, 0.25])
    assert np.array_equal(tex.props.get_color("value1"), [0.2, 0.2, 0.2])  # grey extension
    assert root.children[1].tag == "scene" and root.children[1].type == "scene"


def test_leading_whitespace_before_declaration_keeps_positions():
    text = "\n\n   <?xml version='1.0'?>\n<scene>\n  <bsdf type='diffuse'>\n    <float name='a' value='x'/>"
    text += "</bsdf></scene>"
    err(text, 6, 28)  # the value's first character


def test_spaces_around_equals_and_comments():
    root = parse_string("<scene>\n<!-- hi -->\n<sampler type = 'independent'>"
                        "<integer  name =  \"sampleCount\"  value= '4' /></sampler></scene>")
    assert root.children[0].props.get_int("sampleCount") == 4


def test_defines_and_defaults():
    text = """<scene>
  <default name="spp" value="16"/>
  <default name="kind" value="independent"/>
  <sampler type="$kind"><integer name="sampleCount" value="$spp"/></sampler>
</scene>"""
    assert parse_string(text).children[0].props.get_int("sampleCount") == 16
    root = parse_string(text, defines={"spp": "256"})  # the caller overrides the file's default
    assert root.children[0].type == "independent"
    assert root.children[0].props.get_int("sampleCount") == 256


def test_filename_resolution_for_strings(tmp_path):
    root = parse_string('<scene><mesh type="obj"><string name="filename" value="a/b.obj"/>'
                        '<string name="other" value="c.obj"/></mesh></scene>', base_dir=str(tmp_path))
    props = root.children[0].props
    assert props.get_string("filename") == str(tmp_path / "a" / "b.obj")
    assert props.get_string("other") == "c.obj"  # only 'filename' is a path
    absolute = str(tmp_path / "x.obj")
    root = parse_string(f'<scene><mesh type="obj"><string name="filename" value="{absolute}"/></mesh></scene>')
    assert root.children[0].props.get_string("filename") == absolute


# --- errors -----------------------------------------------------------------------------------------
def test_missing_file(tmp_path):
    missing = tmp_path / "nope.xml"
    with pytest.raises(SceneError) as e:
        parse_file(missing)
    assert str(missing) in str(e.value)


def test_malformed_xml():
    e = err("<scene>\n  <bsdf type='diffuse'>\n  </bsdfx>\n</scene>", 3, 5, "mismatched tag", filename="bad.xml")
    assert str(e).startswith("bad.xml:3:5: malformed XML")  # expat points at the mismatched name


def test_malformed_xml_unclosed_attribute():
    e = err('<scene>\n<bsdf type="diffuse>\n</scene>\n')
    assert "malformed XML" in str(e) and e.location.line >= 2


def test_root_must_be_scene_or_test():
    err("\n<bsdf type='diffuse'/>", 2, 1, "<scene>", "<test")
    err("<test type='ztest'/>", 1, 13, "ttest", "chi2test")


def test_unknown_tag():
    err("<scene>\n  <bsdf type='diffuse'>\n    <colour name='albedo' value='1'/>\n  </bsdf>\n</scene>", 3, 5,
        "unknown tag <colour>", "<color>", "<emitter>")  # lists what is expected


def test_unknown_tag_in_transform_and_op_outside_transform():
    err("<scene><camera type='p'><transform name='toWorld'>\n <shift value='1'/></transform></camera></scene>", 2, 2,
        "<translate>", "<lookat>")
    err("<scene><camera type='p'>\n<translate value='1,2,3'/></camera></scene>", 2, 1,
        "only allowed inside <transform>")


def test_children_of_properties_and_default_placement():
    err("<scene><mesh type='obj'><float name='a' value='1'>\n  <bsdf type='d'/></float></mesh></scene>", 2, 3)
    err("<scene><mesh type='obj'>\n<default name='a' value='1'/></mesh></scene>", 2, 1, "root")


@pytest.mark.parametrize("element, missing", [
    ("<bsdf/>", "type"),
    ("<bsdf type='diffuse'><texture type='checkerboard_color'/></bsdf>", "name"),
    ("<bsdf type='diffuse'><float name='a'/></bsdf>", "value"),
    ("<bsdf type='diffuse'><color value='1 1 1'/></bsdf>", "name"),
    ("<camera type='p'><transform name='t'><rotate axis='0 1 0'/></transform></camera>", "angle"),
    ("<camera type='p'><transform name='t'><lookat origin='0 0 0' target='0 0 1'/></transform></camera>", "up"),
])
def test_missing_attribute(element, missing):
    err(f"<scene>\n{element}\n</scene>", 2, None, f"missing the required attribute '{missing}'")


def test_unexpected_attribute():
    # the location is the offending attribute's name
    err("<scene>\n  <bsdf type='diffuse'>\n    <float name='a' vaule='1'/>\n  </bsdf>\n</scene>", 3, 21,
        "unexpected attribute 'vaule' in <float>", "'value'")
    err("<scene version='4.0'/>", 1, 8, "'version'")   # 0.x to 3.x are Mitsuba's (test_mitsuba_legacy.py)
    err("<scene><bsdf type='diffuse' name='x'/></scene>", None, None,  # only <texture> has a name
        "unexpected attribute 'name'")
    err("<scene><camera type='p'><transform name='t' value='1'/></camera></scene>", None, None,
        "unexpected attribute 'value' in <transform>")


@pytest.mark.parametrize("prop, col, fragment", [
    ("<float name='r' value='1.5x'/>", 24, "bad number '1.5x'"),
    ("<float name='r' value='1 2'/>", 24, "needs 1 number, got 2"),
    ("<float name='r' value=''/>", 24, "empty"),
    ("<point name='c' value='1, two, 3'/>", 24, "bad number 'two'"),
    ("<integer name='n' value='1.5'/>", 26, "bad integer"),
    ("<boolean name='b' value='yes'/>", 26, "true or false"),
])
def test_bad_number(prop, col, fragment):
    err(f"<scene>\n<mesh type='sphere'>\n{prop}\n</mesh>\n</scene>", 3, col, fragment)


def test_wrong_component_count_is_checked_by_the_getter():
    root = parse_string("<scene><mesh type='sphere'>\n<point name='center' value='1 2'/>\n"
                        "<color name='c' value='1 2'/><point name='uv' value='1 2 3'/></mesh></scene>")
    props = root.children[0].props
    with pytest.raises(SceneError) as e:
        props.get_point("center")
    at(e.value, 2, 1)
    assert "needs 3 numbers, got 2" in str(e.value)
    assert np.array_equal(props.get_point2("center"), [1, 2])
    with pytest.raises(SceneError, match="needs 3 numbers \\(or 1 for grey\\), got 2"):
        props.get_color("c")
    with pytest.raises(SceneError, match="needs 2 numbers, got 3"):
        props.get_point2("uv")


def test_duplicate_property():
    err("<scene>\n<mesh type='sphere'>\n  <float name='radius' value='1'/>\n"
        "  <point name='center' value='0 0 0'/>\n  <float name='radius' value='2'/>\n</mesh>\n</scene>", 5, 3,
        "property 'radius' given twice (first at line 3)")


def test_duplicate_property_of_different_kind():
    err("<scene><mesh type='sphere'><float name='radius' value='1'/>\n"
        "<integer name='radius' value='2'/></mesh></scene>", 2, 1, "given twice")


def test_define_that_fills_nothing_is_an_error():
    """As in Mitsuba 3.9.1 ("Found unused parameters"): a -D naming no $name of the file is a mistake."""
    text = "<scene><default name='spp' value='4'/><sampler type='independent'><integer name='sampleCount' value='$spp'/></sampler></scene>"
    assert parse_string(text, "s.xml", defines={"spp": "8"}).children[0].props.get_int("sampleCount") == 8
    with pytest.raises(SceneError) as e:
        parse_string(text, "s.xml", defines={"spp": "8", "sp": "9"})
    assert e.value.location.file == "s.xml" and "-D sp=9" in str(e.value) and "uses $spp" in str(e.value)


def test_undefined_define():
    err("<scene>\n<sampler type='independent'>\n  <integer name='sampleCount' value='$spp'/>\n</sampler>\n</scene>",
        3, 38, "'$spp'", "-D spp=value", defines={"other": "1"})


def test_text_content_is_an_error():
    err("<scene>\n  <bsdf type='diffuse'>\n\n     oops\n  </bsdf>\n</scene>", 4, 6, "'oops'", "<bsdf>")


def test_duplicate_default():
    err("<scene>\n<default name='a' value='1'/>\n<default name='a' value='2'/>\n</scene>", 3, 1, "twice")


def test_columns_count_characters_and_crlf(tmp_path):
    path = tmp_path / "crlf.xml"
    text = "<scene>\r\n<!-- é€ -->\r\n<mesh type='sphere'><!--é--><float name='r' value='x'/></mesh>\r\n</scene>\r\n"
    path.write_bytes(text.encode("utf-8"))
    with pytest.raises(SceneError) as e:
        parse_file(path)
    at(e.value, 3, 52)
