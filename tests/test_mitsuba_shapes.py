"""Mitsuba 3's parametric shapes (rectangle, disk, cylinder, sphere): geometry and uv parametrisation as Mitsuba
3.9 gives them (facts read off its own intersections: the formulas in each plugin's docstring), the errors, and the
flip_normals of an analytic sphere. Whole renders against Mitsuba are the twin scene shapes_parametric
(tests/test_mitsuba_twins.py)."""
import numpy as np
import pytest

import clrender.plugins  # noqa: F401  (registers every plugin)
from clrender.errors import SceneError
from clrender.scene import registry
from clrender.shapes.cylinder import axis_frame, cylinder_mesh
from clrender.shapes.disk import disk_mesh
from clrender.shapes.rectangle import rectangle_mesh


def surface_points(mesh, n=2000, seed=1):
    """Random points on the mesh: (position, interpolated uv, interpolated normal or None, face normal)."""
    rng = np.random.default_rng(seed)
    f = rng.integers(0, len(mesh.faces), n)
    b = rng.random((n, 2))
    flip = b.sum(1) > 1
    b[flip] = 1 - b[flip]
    w = np.c_[1 - b.sum(1), b]
    idx = mesh.faces[f]
    p = np.einsum("ij,ijk->ik", w, mesh.positions[idx].astype(np.float64))
    uv = np.einsum("ij,ijk->ik", w, mesh.uvs[idx].astype(np.float64))
    tri = mesh.positions[idx].astype(np.float64)
    ng = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    ng /= np.linalg.norm(ng, axis=1, keepdims=True)
    ns = None
    if mesh.normals is not None:
        ns = np.einsum("ij,ijk->ik", w, mesh.normals[idx].astype(np.float64))
        ns /= np.linalg.norm(ns, axis=1, keepdims=True)
    return p, uv, ns, ng


def test_rectangle_is_mitsubas():
    p, uv, ns, ng = surface_points(rectangle_mesh())
    assert np.all(np.abs(p[:, :2]) <= 1) and np.all(p[:, 2] == 0)
    np.testing.assert_allclose(uv, (p[:, :2] + 1) / 2, atol=1e-6)
    np.testing.assert_allclose(ng, np.tile([0, 0, 1], (len(ng), 1)), atol=1e-12)


def test_disk_is_mitsubas():
    m = disk_mesh()
    p, uv, ns, ng = surface_points(m)
    r = np.hypot(p[:, 0], p[:, 1])
    phi = np.mod(np.arctan2(p[:, 1], p[:, 0]), 2 * np.pi)
    assert np.all(r <= 1 + 1e-6) and np.all(p[:, 2] == 0)
    np.testing.assert_allclose(ng[:, 2], 1)
    # uv = (r, phi / 2pi): within the tessellation's error (a sector spans 2pi / 512)
    assert np.abs(uv[:, 0] - r).max() < 2e-4
    dv = np.abs(uv[:, 1] - phi / (2 * np.pi))
    dv = np.minimum(dv, 1 - dv)   # the seam
    assert dv.max() < 1.0 / 512
    area = 0.5 * np.linalg.norm(np.cross(*(m.positions[m.faces][:, 1:] - m.positions[m.faces][:, :1]).transpose(1, 0, 2)),
                                axis=1).sum()
    assert area == pytest.approx(np.pi, rel=5e-5)


def test_cylinder_is_mitsubas():
    p0, p1, r = np.array([0.5, -1.0, 2.0]), np.array([1.0, 1.0, 0.0]), 0.3
    m = cylinder_mesh(p0, p1, r)
    p, uv, ns, ng = surface_points(m)
    axis = (p1 - p0) / np.linalg.norm(p1 - p0)
    s, t = axis_frame(axis)
    np.testing.assert_allclose([s @ t, s @ axis, t @ axis], 0, atol=1e-12)
    np.testing.assert_allclose(np.cross(s, t), axis, atol=1e-12)
    d = p - p0
    z = d @ axis / np.linalg.norm(p1 - p0)
    radial = d - np.outer(d @ axis, axis)
    rr = np.linalg.norm(radial, axis=1)
    phi = np.mod(np.arctan2(radial @ t, radial @ s), 2 * np.pi)
    assert np.all((rr <= r + 1e-6) & (rr > r * (1 - 2e-5)))
    np.testing.assert_allclose(uv[:, 1], z, atol=1e-6)
    du = np.abs(uv[:, 0] - phi / (2 * np.pi))
    assert np.minimum(du, 1 - du).max() < 1e-5
    # shading normals: radial, outward; face normals outward too
    np.testing.assert_allclose(ns, radial / rr[:, None], atol=1e-5)
    assert np.all(np.einsum("ij,ij->i", ng, radial) > 0)


def test_default_cylinder_frame_is_identity():
    s, t = axis_frame(np.array([0.0, 0.0, 1.0]))
    np.testing.assert_allclose(s, [1, 0, 0])
    np.testing.assert_allclose(t, [0, 1, 0])


def make(type_name, **props):
    return registry.instantiate("shape", type_name, props, fmt="mitsuba")


def test_sphere_to_world_and_errors():
    from clrender.scene.transform import Transform

    m = np.eye(4)
    m[:3, :3] *= 2.0
    m[:3, 3] = [1, 2, 3]
    s = make("sphere", center=("point", [1.0, 0.0, 0.0]), radius=("float", 0.5), to_world=("transform", Transform(m)))
    np.testing.assert_allclose(s.center, [3, 2, 3])
    assert s.radius == pytest.approx(1.0)
    m[0, 0] = 3.0
    with pytest.raises(SceneError, match="uniformly"):
        make("sphere", to_world=("transform", Transform(m)))
    with pytest.raises(SceneError, match="positive radius"):
        make("sphere", radius=("float", -1.0))
    with pytest.raises(SceneError, match="distinct"):
        make("cylinder", p0=("point", [0.0, 0.0, 1.0]))
    with pytest.raises(SceneError, match="radius"):
        make("cylinder", radius=("float", 0.0))
    with pytest.raises(SceneError, match="unused|not used|unknown"):
        make("disk", radius=("float", 2.0))


def test_flipped_sphere_faces_inward():
    """flip_normals turns the analytic sphere's normals inward: from outside a diffuse flipped sphere is black,
    from inside it is lit (the normals integrator would show the sign; here the packed flag drives the kernel)."""
    from clrender.device import dispatch
    from clrender.pack import PackContext
    from clrender.device import layout

    s = make("sphere", flip_normals=("boolean", True))
    row = layout.zeros("Shape")[0]
    s.pack(PackContext(), 0, row)
    assert row["flags"] & dispatch.flag_defines()["SHAPE_FLIP_NORMALS"]
    row2 = layout.zeros("Shape")[0]
    make("sphere").pack(PackContext(), 0, row2)
    assert not row2["flags"] & dispatch.flag_defines()["SHAPE_FLIP_NORMALS"]


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


def test_sphere_frame_quaternion():
    """p.sphere.rot turns a vector as the sphere's to_world (rotation, or mirror) does: checked on random frames,
    half turns (w = 0) and mirrors (w's sign bit)."""
    from clrender.scene.transform import Transform
    from clrender.shapes.sphere import frame_quaternion

    def turn(q, v):   # as kernels/shapes/sphere.h reads the row, forwards
        u, w = q[:3].astype(np.float64), abs(float(q[3]))
        r = v + 2 * w * np.cross(u, v) + 2 * np.cross(u, np.cross(u, v))
        return -r if np.signbit(q[3]) else r

    rng = np.random.default_rng(5)
    frames = [Transform.rotate(a, 180.0).matrix[:3, :3] for a in np.eye(3)]
    frames += [Transform.rotate(rng.normal(size=3), rng.uniform(-360, 360)).matrix[:3, :3] for _ in range(200)]
    frames += [f @ np.diag([1, 1, -1]) for f in frames]
    for m in frames:
        q = frame_quaternion(m)
        assert abs(np.linalg.norm(q) - 1) < 1e-6 and bool(np.signbit(q[3])) == (np.linalg.det(m) < 0)
        for v in rng.normal(size=(3, 3)):
            np.testing.assert_allclose(turn(q, v), m @ v, atol=1e-5)


@pytest.mark.parametrize("xform, view, expect", [
    ("", "0, 0, 5", "top"),                                          # unturned: v < 1/2 faces +z
    ('<rotate x="1" angle="180"/>', "0, 0, 5", "bottom"),
    ('<scale z="-1"/>', "0, 0, 5", "bottom"),                        # a mirror (inside out: flip_normals below)
    ('<rotate z="1" angle="90"/>', "5, 0, 0", "right"),              # u in (1/2, 1) faces +x
], ids=["identity", "half turn", "mirror", "quarter turn"])
def test_sphere_uv_turns_with_to_world(tmp_path, xform, view, expect):
    """Mitsuba's sphere takes uv in its own frame, which to_world turns (it was taken in world axes): an emitting
    sphere whose radiance is red on one half of its uv square and blue on the other, seen from one side, shows one
    colour only. A mirror turns Mitsuba's sphere inside out, so that one also has flip_normals."""
    import clrender

    from PIL import Image

    halves = [[(255, 0, 0), (0, 0, 255)]]            # red for u < 1/2 (or v < 1/2), blue beyond
    img = np.array(halves if expect in ("left", "right") else np.transpose(halves, (1, 0, 2)), np.uint8)
    Image.fromarray(img).save(tmp_path / "halves.png")
    flip = '<boolean name="flip_normals" value="true"/>' if "scale" in xform else ""
    xml = f"""<scene version="3.0.0">
        <sensor type="perspective"><float name="fov" value="20"/>
            <transform name="to_world"><lookat origin="{view}" target="0, 0, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/></film></sensor>
        <shape type="sphere">{flip}<transform name="to_world">{xform}</transform>
            <emitter type="area"><texture type="bitmap" name="radiance"><string name="filename" value="halves.png"/>
                <string name="filter_type" value="nearest"/><boolean name="raw" value="true"/></texture></emitter>
        </shape></scene>"""
    (tmp_path / "s.xml").write_text(xml)
    film = clrender.render(clrender.load_scene(tmp_path / "s.xml"), spp=16, seed=1)
    red, blue = film.image[..., 0].sum(), film.image[..., 2].sum()
    assert red + blue > 20, "the sphere is not in view"
    if expect in ("top", "left"):
        assert blue == 0, (red, blue)
    else:
        assert red == 0, (red, blue)
    if flip:   # without flip_normals the mirrored sphere's light faces inward, as in Mitsuba: black from outside
        (tmp_path / "s.xml").write_text(xml.replace(flip, ""))
        assert clrender.render(clrender.load_scene(tmp_path / "s.xml"), spp=4, seed=1).image.max() == 0


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
