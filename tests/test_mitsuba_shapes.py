"""Mitsuba 3's shapes where no one shape is the subject: the default BSDF of emitters, anisotropy following dp/du on
spheres and meshes, instancing (shapegroup + instance, flattened when read) and its errors, a mesh of degenerate
triangles. Each shape's own tests are tests/shapes/test_<name>.py; whole renders against Mitsuba are the twin scene
shapes_parametric (tests/test_mitsuba_twins.py)."""
import numpy as np
import pytest

import clrender.plugins  # noqa: F401  (registers every plugin)
from clrender.errors import SceneError
from clrender.scene import registry


def make(type_name, **props):
    return registry.instantiate("shape", type_name, props, fmt="mitsuba")


def test_default_bsdf_is_black_on_emitters_as_in_mitsuba():
    """Mitsuba 3 gives a shape without a BSDF a diffuse one of reflectance 0.5, but 0 when the shape emits (an area
    light reflects nothing); Nori gives 0.5 to both. Leaving it at 0.5 made the shapes_parametric twin 0.6 % too
    bright (light bouncing off the underside of its lamp)."""
    from clrender.scene.xmlparser import parse_string

    def shape(fmt, emits):
        body = '<emitter type="area"><rgb name="radiance" value="1"/></emitter>' if emits else ""
        if fmt == "mitsuba":
            text = f'<scene version="3.0.0"><shape type="sphere">{body}</shape></scene>'
        else:
            text = f'<scene><mesh type="sphere">{body.replace("rgb", "color")}</mesh></scene>'
        spec = parse_string(text)
        assert spec.children[0].format == fmt
        return registry.create(spec.children[0])

    assert np.all(shape("mitsuba", True).bsdf.albedo == 0)
    assert np.all(shape("mitsuba", False).bsdf.albedo == 0.5)
    assert np.all(shape("nori", True).bsdf.albedo == 0.5)


# ------------------------------------------------------------------------------- anisotropy follows dp/du
ANISO_SCENE = """<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="30"/>
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="12"/>
            <rfilter type="box"/></film></sensor>
    <shape type="rectangle"><transform name="to_world"><scale x="2" y="0.3"/><rotate x="1" angle="150"/>
        <translate y="2" z="1"/></transform><emitter type="area"><rgb name="radiance" value="20"/></emitter></shape>
    <emitter type="constant"><rgb name="radiance" value="0.05"/></emitter>
    {shape}
</scene>"""


def aniso_bsdf(au, av):
    return (f'<bsdf type="roughconductor"><string name="distribution" value="ggx"/>'
            f'<float name="alpha_u" value="{au}"/><float name="alpha_v" value="{av}"/></bsdf>')


def render_aniso(tmp_path, shape, seed):
    import clrender

    (tmp_path / "a.xml").write_text(ANISO_SCENE.format(shape=shape))
    return clrender.render(clrender.load_scene(tmp_path / "a.xml"), spp=256, seed=seed)


def test_anisotropy_follows_the_spheres_dp_du(tmp_path):
    """alpha_u runs along dp/du, which on Mitsuba's sphere points along phi about its own pole (to_world turns it;
    clrender's frame once ignored it): turning the sphere about its pole changes nothing, tipping the pole does."""
    from clrender.testing.stats import compare_films

    def sphere(rot):
        return (f'<shape type="sphere"><transform name="to_world">{rot}<scale value="1.2"/></transform>'
                f'{aniso_bsdf(0.03, 0.5)}</shape>')

    a = render_aniso(tmp_path, sphere(""), 1)
    b = render_aniso(tmp_path, sphere('<rotate z="1" angle="70"/>'), 2)
    c = render_aniso(tmp_path, sphere('<rotate x="1" angle="90"/>'), 3)
    assert compare_films(a, b).passed, compare_films(a, b).message
    assert not compare_films(a, c).passed


def test_anisotropy_follows_the_meshs_uvs(tmp_path):
    """On a mesh dp/du comes from its uvs: the same quad with uvs turned a quarter and alpha_u, alpha_v swapped
    renders the same; with only the uvs turned it does not."""
    from clrender.testing.stats import compare_films

    def quad(name, uvs):
        vt = "".join(f"vt {u} {v}\n" for u, v in uvs)
        (tmp_path / name).write_text("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n" + vt + "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")

    quad("u_along_x.obj", [(0, 0), (1, 0), (1, 1), (0, 1)])
    quad("u_along_y.obj", [(0, 1), (0, 0), (1, 0), (1, 1)])

    def shape(name, au, av):
        return (f'<shape type="obj"><string name="filename" value="{tmp_path / name}"/><transform name="to_world">'
                f'<rotate x="1" angle="-30"/><scale value="1.2"/></transform>{aniso_bsdf(au, av)}</shape>')

    a = render_aniso(tmp_path, shape("u_along_x.obj", 0.03, 0.5), 1)
    b = render_aniso(tmp_path, shape("u_along_y.obj", 0.5, 0.03), 2)
    c = render_aniso(tmp_path, shape("u_along_y.obj", 0.03, 0.5), 3)
    assert compare_films(a, b).passed, compare_films(a, b).message
    assert not compare_films(a, c).passed


# --- instancing: shapegroup + instance, flattened when the scene is read -------------------------------------------

def _mitsuba_scene(body: str):
    from clrender.scene.xmlparser import parse_string

    sensor = ('<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>'
              '<integer name="height" value="6"/></film></sensor>')
    return registry.create(parse_string(f'<scene version="3.0.0">{sensor}{body}</scene>', "i.xml"))


GROUP = ('<shape type="shapegroup" id="g"><shape type="cube"><transform name="to_world"><translate value="0, 1, 0"/>'
         '</transform></shape><shape type="sphere"><point name="center" value="2, 0, 0"/>'
         '<float name="radius" value="0.5"/></shape></shape>')


def test_instances_are_copies_of_the_group_under_their_to_world():
    """A shapegroup alone renders nothing; each instance adds its group's shapes, mapped by its to_world (a mesh's
    vertices, a sphere's centre, radius and frame); a mirroring instance reverses the winding, so that the face
    normals stay the inverse-transpose image of the group's (the instance maps normals as covectors)."""
    assert _mitsuba_scene(GROUP + '<shape type="rectangle"/>').shapes[0].spec.type == "rectangle"
    xform = '<transform name="to_world"><scale value="-2, 2, 2"/><rotate y="1" angle="30"/><translate value="1, 2, 3"/></transform>'
    scene = _mitsuba_scene(GROUP + '<shape type="instance"><ref id="g"/></shape>'
                           f'<shape type="instance"><ref id="g"/>{xform}</shape>')
    assert [s.spec.type for s in scene.shapes] == ["cube", "sphere", "cube", "sphere"]
    cube, sphere, cube2, sphere2 = scene.shapes
    m = _mitsuba_scene(f'<shape type="sphere">{xform}</shape>').shapes[0]   # its to_world, via the sphere's frame
    lin = m.frame * m.radius
    t = m.center
    np.testing.assert_allclose(cube2.mesh.positions, cube.mesh.positions @ lin.T + t, atol=1e-5)
    np.testing.assert_allclose(sphere2.center, lin @ sphere.center + t, atol=1e-6)
    assert sphere2.radius == pytest.approx(2 * sphere.radius)
    assert not sphere2.flip_normals    # an instance's mirror does not turn a sphere inside out
    def face_normals(mesh):
        tri = mesh.positions[mesh.faces].astype(np.float64)
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        return n / np.linalg.norm(n, axis=1, keepdims=True)
    mapped = face_normals(cube.mesh) @ np.linalg.inv(lin)
    mapped /= np.linalg.norm(mapped, axis=1, keepdims=True)
    np.testing.assert_allclose(face_normals(cube2.mesh), mapped, atol=1e-5)
    assert cube2.bsdf is cube.bsdf


@pytest.mark.parametrize("body, message", [
    ('<shape type="shapegroup" id="g"><shape type="sphere"><emitter type="area"/></shape></shape>',
     "cannot carry an emitter"),
    ('<shape type="shapegroup" id="g"><shape type="shapegroup"><shape type="sphere"/></shape></shape>',
     "nested instancing"),
    ('<shape type="instance"><shape type="sphere"/></shape>', "takes one shapegroup"),
    ('<shape type="instance"/>', "exactly one shapegroup"),
    ('<shape type="shapegroup" id="g"><shape type="sphere"/></shape><shape type="instance"><ref id="g"/>'
     '<transform name="to_world"><scale value="1, 2, 1"/></transform></shape>', "scale it uniformly"),
])
def test_instancing_errors_are_located(body, message):
    with pytest.raises(SceneError, match=message) as e:
        _mitsuba_scene(body)
    assert e.value.location is not None and e.value.location.file == "i.xml"


# --- a mesh without a triangle of non-zero area (Bitterli's staircase has one) ------------------------------------

def test_mesh_of_degenerate_triangles_is_left_out_with_a_warning(tmp_path, caplog):
    """Mitsuba 3.9.1 loads such a mesh (no warning where the file has normals) and renders the scene around it, since
    a zero-area triangle is never hit; clrender leaves it out, saying so with the file's name. The scene then renders
    exactly as without it (same samples). An emitting one is refused, as Mitsuba's area distribution refuses it; a
    Nori file keeps its error (tests/test_corpus.py)."""
    import logging

    import clrender

    (tmp_path / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 1 0 0\nf 1 2 3\nf 4 1 2\n")
    head = ('<scene version="3.0.0"><sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" '
            'target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm"><integer name="width" value="8"/>'
            '<integer name="height" value="6"/></film></sensor><shape type="sphere"/><emitter type="constant"/>')
    flat = '<shape type="obj"><string name="filename" value="flat.obj"/>'
    (tmp_path / "with.xml").write_text(f"{head}{flat}</shape></scene>")
    (tmp_path / "without.xml").write_text(f"{head}</scene>")
    with caplog.at_level(logging.WARNING, logger="clrender"):
        scene = clrender.load_scene(tmp_path / "with.xml")
    assert [s.spec.type for s in scene.shapes] == ["sphere"]
    assert any("flat.obj" in r.getMessage() and "left out" in r.getMessage() for r in caplog.records)
    a = clrender.render(scene, spp=4, seed=1).image
    b = clrender.render(clrender.load_scene(tmp_path / "without.xml"), spp=4, seed=1).image
    assert a.mean() > 0
    np.testing.assert_array_equal(a, b)
    (tmp_path / "lit.xml").write_text(f'{head}{flat}<emitter type="area"/></shape></scene>')
    with pytest.raises(SceneError, match="no non-degenerate triangles.*some area") as e:
        clrender.load_scene(tmp_path / "lit.xml")
    assert e.value.location.file.endswith("lit.xml")
