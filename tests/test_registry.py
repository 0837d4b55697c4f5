"""Plugin registry and create(): lookup errors, nesting rules, property use checks, all located."""
import numpy as np
import pytest

from clrender.errors import SceneError
from clrender.scene import registry
from clrender.scene.properties import PropertyList
from clrender.scene.registry import create, lookup, register, registered
from clrender.scene.xmlparser import parse_string

# Type names with a prefix no real plugin uses, removed again after each test.
T = "zz_test_"
constructed: list[str] = []


@pytest.fixture(autouse=True)
def test_plugins():
    constructed.clear()

    @register("mesh", T + "mesh")
    class Mesh:
        children = ("bsdf", "emitter")

        def __init__(self, props, children, spec):
            self.radius = props.get_float("radius")
            self.center = props.get_point("center", [0, 0, 0])
            self.kids = children
            constructed.append("mesh")

    @register("bsdf", T + "diffuse")
    class Diffuse:
        def __init__(self, props, children, spec):
            self.albedo = props.get_color("albedo", 0.5)
            constructed.append("bsdf")

    @register("emitter", T + "area")
    class Area:
        def __init__(self, props, children, spec):
            self.radiance = props.get_color("radiance")
            constructed.append("emitter")

    @register("bsdf", T + "fails")
    class Fails:
        def __init__(self, props, children, spec):
            raise SceneError("custom failure", spec.location)

    yield
    for tag, name in [("mesh", T + "mesh"), ("bsdf", T + "diffuse"),
                      ("emitter", T + "area"), ("bsdf", T + "fails")]:
        registry.unregister(tag, name)


def spec_of(body: str):
    """The first child of a <scene> wrapping ``body`` (which starts on line 2)."""
    return parse_string(f"<scene>\n{body}\n</scene>").children[0]


def make(body: str):
    return create(spec_of(body))


def test_register_lookup_registered():
    assert lookup("mesh", T + "mesh").__name__ == "Mesh"
    assert T + "diffuse" in registered("bsdf") and T + "fails" in registered("bsdf")
    assert T + "diffuse" not in registered("mesh")
    assert registered("bsdf") == sorted(registered("bsdf"))


def test_duplicate_registration_is_a_programming_error():
    with pytest.raises(RuntimeError, match="registered twice"):
        @register("bsdf", T + "diffuse")
        class Again:
            pass
    with pytest.raises(RuntimeError, match="unknown Nori object tag"):
        register("bdsf", T + "x")
    with pytest.raises(RuntimeError, match="unknown Mitsuba 3 object tag"):
        register("mesh", T + "x", fmt="mitsuba")
    with pytest.raises(RuntimeError, match="unknown scene format"):
        register("bsdf", T + "x", fmt="pbrt")


def test_formats_are_separate_namespaces():
    """A Mitsuba file's <bsdf type=...> never finds a Nori plugin of that name, and errors say which reader."""
    @register("bsdf", T + "diffuse", fmt="mitsuba")
    class MitsubaDiffuse:
        def __init__(self, props, children, spec):
            self.reflectance = props.get_color("reflectance", 0.5)
    try:
        assert lookup("bsdf", T + "diffuse", fmt="mitsuba") is MitsubaDiffuse
        assert lookup("bsdf", T + "diffuse").__name__ == "Diffuse"
        assert T + "fails" not in registered("bsdf", "mitsuba")
        with pytest.raises(SceneError, match=r"read as a Mitsuba 3 scene.*known: .*" + T + "diffuse"):
            lookup("bsdf", T + "fails", fmt="mitsuba")
        b = registry.instantiate("bsdf", T + "diffuse", {"reflectance": ("color", [0.25, 0.25, 0.25])}, fmt="mitsuba")
        assert np.allclose(b.reflectance, 0.25) and b.spec.format == "mitsuba"
    finally:
        registry.unregister("bsdf", T + "diffuse", fmt="mitsuba")


def test_create_builds_children_first_and_attaches_spec():
    m = make(f"""<mesh type="{T}mesh">
  <float name="radius" value="2"/>
  <bsdf type="{T}diffuse"><color name="albedo" value="0.1 0.2 0.3"/></bsdf>
  <emitter type="{T}area"><color name="radiance" value="4"/></emitter>
</mesh>""")
    assert constructed == ["bsdf", "emitter", "mesh"]
    assert m.radius == 2.0 and np.array_equal(m.center, [0, 0, 0])
    bsdf, emitter = m.kids
    assert np.allclose(bsdf.albedo, [0.1, 0.2, 0.3])
    assert np.array_equal(emitter.radiance, [4, 4, 4])
    assert m.spec.type == T + "mesh" and bsdf.spec.tag == "bsdf" and emitter.spec.location.line == 5


def test_get_float_accepts_integer_and_defaults_apply():
    m = make(f'<mesh type="{T}mesh"><integer name="radius" value="3"/><bsdf type="{T}diffuse"/></mesh>')
    assert m.radius == 3.0 and isinstance(m.radius, float)
    assert np.array_equal(m.kids[0].albedo, [0.5, 0.5, 0.5])


def test_unknown_plugin_type():
    with pytest.raises(SceneError) as e:
        make(f'<mesh type="{T}mesh"><float name="radius" value="1"/>\n   <bsdf type="difuse"/></mesh>')
    assert e.value.location.line == 3 and e.value.location.col == 4
    msg = str(e.value)
    assert "unknown bsdf type 'difuse'; known: " in msg and T + "diffuse" in msg
    assert constructed == []  # nothing was built before the error


def test_nested_child_not_accepted():
    with pytest.raises(SceneError) as e:
        make(f"""<bsdf type="{T}diffuse">
    <emitter type="{T}area"><color name="radiance" value="1"/></emitter>
</bsdf>""")
    assert e.value.location.line == 3 and e.value.location.col == 5
    assert f'<emitter> cannot be nested in <bsdf type="{T}diffuse">' in str(e.value)
    assert constructed == []


def test_unused_property():
    with pytest.raises(SceneError) as e:
        make(f"""<bsdf type="{T}diffuse">
  <color name="albedo" value="1"/>
  <float name="roughness" value="0.1"/>
</bsdf>""")
    assert e.value.location.line == 4 and e.value.location.col == 3
    assert str(e.value).endswith(f"property 'roughness' is not used by <bsdf type=\"{T}diffuse\">")


def test_missing_required_property():
    with pytest.raises(SceneError) as e:
        make(f'<mesh type="{T}mesh">\n<bsdf type="{T}diffuse"/><emitter type="{T}area"/>\n'
             '<float name="radius" value="1"/></mesh>')
    # Reported at the owner (the emitter element on line 3), naming the kind expected.
    col = len(f'<bsdf type="{T}diffuse"/>') + 1
    assert e.value.location.line == 3 and e.value.location.col == col
    assert f"missing required property 'radiance' (color) of <emitter type=\"{T}area\">" in str(e.value)


def test_wrong_property_kind():
    with pytest.raises(SceneError) as e:
        make(f'<mesh type="{T}mesh">\n  <color name="radius" value="1 1 1"/>\n</mesh>')
    assert e.value.location.line == 3 and e.value.location.col == 3
    assert "property 'radius' is a <color>" in str(e.value) and "<float>" in str(e.value)


def test_scene_error_from_constructor_propagates():
    spec = spec_of(f'<bsdf type="{T}fails"/>')
    with pytest.raises(SceneError) as e:
        create(spec)
    assert str(e.value) == f"{spec.location}: custom failure"


def test_property_list_in_code():
    props = PropertyList('<bsdf type="x">')
    props.add("n", "integer", 3)
    props.add("v", "vector", [1, 2, 3])
    assert props.has("n") and not props.has("m")
    with pytest.raises(SceneError, match="property 'n' is not used"):
        props.check_unused()  # has() does not mark a property used
    assert props.get_int("n") == 3
    with pytest.raises(SceneError, match="property 'v' is not used"):
        props.check_unused()
    got = props.get_vector("v")
    got[0] = 99  # getters return copies
    assert props.get_vector("v")[0] == 1
    props.check_unused()
    with pytest.raises(SceneError, match="given twice"):
        props.add("n", "integer", 4)
    with pytest.raises(SceneError, match="is a <vector>"):
        props.get_point("v")
    assert props.get_transform("missing").is_identity()
    assert props.get_float("missing", None) is None
