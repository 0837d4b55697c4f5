"""Mitsuba 3's mesh_attribute texture (clrender/textures/mesh_attribute.py, kernels/textures/mesh_attribute.h): a
PLY's vertex and face attributes named as Mitsuba names them, rendered as a diffuse reflectance (vertex colours
interpolated, face colours) and as a blend's weight (a one-value face attribute) against the attribute where each
pixel looks, and the located errors. Its values exist only at a mesh's hits, so its evaluation is checked through
the render."""
import numpy as np
import pytest

from clrender.errors import SceneError

BLACK, WHITE = ('<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>',
                '<bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf>')


def write_attribute_ply(path):
    """A 4 x 4 square at z = 1 facing +z, two triangles: vertex colours `color_0..2` (floats) affine in x and y,
    face colours `color_0..2`, and face bytes `w_r w_g w_b` (Mitsuba normalises and sRGB-decodes integer fields)."""
    import struct

    xy = np.array([[-2, -2], [2, -2], [2, 2], [-2, 2]], np.float64)
    colors = np.stack([vertex_color_at(x, y) for x, y in xy])
    faces = [(0, 1, 2), (0, 2, 3)]
    face_colors = np.array([[0.9, 0.2, 0.1], [0.1, 0.5, 0.8]])
    head = ("ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nproperty float color_0\nproperty float color_1\nproperty float color_2\n"
            "element face 2\nproperty list uchar int vertex_indices\nproperty float color_0\nproperty float color_1\n"
            "property float color_2\nproperty uchar w_r\nproperty uchar w_g\nproperty uchar w_b\n"
            "property float weight_0\nend_header\n")
    body = b"".join(struct.pack("<6f", x, y, 1.0, *c) for (x, y), c in zip(xy, colors))
    body += b"".join(struct.pack("<B3i3f3Bf", 3, *f, *c, 255, 128, 0, w)
                     for f, c, w in zip(faces, face_colors, FACE_WEIGHTS))
    path.write_bytes(head.encode() + body)
    return face_colors


FACE_WEIGHTS = (0.25, 0.7)


def vertex_color_at(x, y):
    return np.array([0.5 + 0.1 * x + 0.05 * y, 0.4 - 0.05 * x + 0.1 * y, 0.6 + 0.05 * x - 0.05 * y])


def test_ply_attributes_are_named_as_mitsuba_names_them(tmp_path):
    from clrender.shapes.plyfile import load_ply
    from clrender.textures.imagefile import srgb_to_linear

    face_colors = write_attribute_ply(tmp_path / "a.ply")
    m = load_ply(tmp_path / "a.ply")
    assert sorted(m.attributes) == ["face_color", "face_w_color", "face_weight", "vertex_color"]
    np.testing.assert_allclose(m.attributes["face_color"], face_colors, atol=1e-7)
    np.testing.assert_allclose(m.attributes["face_w_color"][0], [1.0, srgb_to_linear(128 / 255), 0.0])
    np.testing.assert_allclose(m.attributes["vertex_color"][2], vertex_color_at(2, 2), atol=1e-7)


@pytest.mark.plugin("mesh_attribute", "eval")
@pytest.mark.plugin("mesh_attribute", "render")
@pytest.mark.parametrize("attribute", ["vertex_color", "face_color", "face_weight"])
def test_mesh_attribute_renders_the_attribute(tmp_path, attribute):
    """A diffuse square under a unit sky, seen by `direct`: each pixel is the reflectance where it looks, here the
    vertex colours interpolated barycentrically (an affine function over the square, so a box-filtered pixel is its
    value at the hit of the pixel's centre) or the face's colour (pixels off the diagonal); a one-value face
    attribute as a blendbsdf's weight between black and white gives that weight. Where each pixel looks is the aov
    integrator's `position`; z-tested per pixel. Mitsuba 3.9.1 renders Mitsuba's own attribute sphere
    (tests/scenes/mesh_attributes) within the noise of both (checked by hand)."""
    import clrender
    from clrender.testing.stats import compare_to_value

    face_colors = write_attribute_ply(tmp_path / "a.ply")
    scene = ('<scene version="3.0.0">{integrator}<sensor type="perspective">'
             '<transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 1" up="0, 1, 0"/></transform>'
             '<film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="12"/>'
             '<rfilter type="box"/></film></sensor><emitter type="constant"/><shape type="ply">'
             '<string name="filename" value="a.ply"/>{bsdf}</shape></scene>')
    texture = f'<string name="name" value="{attribute}"/></texture>'
    if attribute == "face_weight":
        bsdf = (f'<bsdf type="blendbsdf"><texture type="mesh_attribute" name="weight">{texture}{BLACK}{WHITE}'
                '</bsdf>')
    else:
        bsdf = f'<bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance">{texture}</bsdf>'
    scene = scene.replace("{bsdf}", bsdf)
    (tmp_path / "s.xml").write_text(scene.format(integrator='<integrator type="direct"/>'))
    (tmp_path / "p.xml").write_text(scene.format(
        integrator='<integrator type="aov"><string name="aovs" value="p:position"/></integrator>'))
    p = clrender.render(clrender.load_scene(tmp_path / "p.xml"), spp=16, seed=1).image.astype(np.float64)
    assert np.allclose(p[..., 2], 1.0, atol=1e-4)   # every pixel sees the square
    x, y = p[..., 0], p[..., 1]
    if attribute == "vertex_color":
        expected, mask = np.moveaxis(vertex_color_at(x, y), 0, -1), np.ones(x.shape, bool)
    else:
        pitch = np.abs(np.diff(x, axis=1)).max()
        per_face = face_colors if attribute == "face_color" else np.repeat(np.array(FACE_WEIGHTS)[:, None], 3, 1)
        expected = np.where((y < x)[..., None], per_face[0], per_face[1])
        mask = np.abs(y - x) / np.sqrt(2) > pitch
    film = clrender.render(clrender.load_scene(tmp_path / "s.xml"), spp=256, seed=2)
    result = compare_to_value(film, expected, mask=mask)
    assert result.passed, result.message


def test_mesh_attribute_errors(tmp_path):
    import clrender

    write_attribute_ply(tmp_path / "a.ply")
    base = ('<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/>'
            '<integer name="height" value="4"/></film></sensor><shape type="{shape}"><string name="filename" '
            'value="a.ply"/><bsdf type="{bsdf}">{extra}<texture type="mesh_attribute" name="{param}"><string '
            'name="name" value="{name}"/></texture></bsdf></shape></scene>')
    cases = [(dict(name="color"), 'must start with "vertex_" or "face_"'),
             (dict(name="vertex_nope"), 'has no attribute "vertex_nope" (it has: face_color, face_w_color, face_weight, '
                                        'vertex_color)'),
             (dict(bsdf="blendbsdf", param="weight", name="face_weight",
                   extra='<bsdf type="diffuse"><texture type="checkerboard" name="reflectance"/></bsdf>'
                         '<bsdf type="diffuse"/>'), "reads another texture beside it")]
    for kw, message in cases:
        fields = dict(shape="ply", bsdf="diffuse", extra="", param="reflectance", name="vertex_color")
        fields.update(kw)
        (tmp_path / "e.xml").write_text(base.format(**fields))
        with pytest.raises(SceneError) as e:
            clrender.load_scene(tmp_path / "e.xml")
        assert message in str(e.value) and e.value.location.file.endswith("e.xml"), str(e.value)
