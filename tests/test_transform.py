"""Transforms against hand-computed matrices, both directly and through the XML <transform> ops."""
import numpy as np
import pytest

from clrender.errors import SceneError
from clrender.scene.transform import Transform
from clrender.scene.xmlparser import parse_string


def xml_transform(ops: str) -> Transform:
    spec = parse_string(f"""<scene><camera type="perspective">
<transform name="toWorld">
{ops}
</transform></camera></scene>""")
    return spec.children[0].props.get_transform("toWorld")


def test_identity_default():
    t = Transform()
    assert np.array_equal(t.matrix, np.eye(4))
    assert t.is_identity()
    assert not Transform.translate([0, 0, 1]).is_identity()


def test_translate():
    t = xml_transform('<translate value="1, 2 3"/>')
    expected = np.array([[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]], float)
    assert np.array_equal(t.matrix, expected)
    assert np.allclose(t.apply_point([1, 1, 1]), [2, 3, 4])
    assert np.allclose(t.apply_vector([1, 1, 1]), [1, 1, 1])  # directions ignore translation


def test_scale_single_value():
    t = xml_transform('<scale value="2"/>')
    assert np.array_equal(t.matrix, np.diag([2.0, 2.0, 2.0, 1.0]))


def test_scale_three_values():
    t = xml_transform('<scale value="2,3,4"/>')
    assert np.array_equal(t.matrix, np.diag([2.0, 3.0, 4.0, 1.0]))
    assert np.allclose(t.inverse.matrix, np.diag([0.5, 1 / 3, 0.25, 1.0]))


def test_rotate_90_about_z_is_right_handed():
    t = xml_transform('<rotate axis="0,0,1" angle="90"/>')
    expected = np.array([[0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], float)
    assert np.allclose(t.matrix, expected, atol=1e-15)
    assert np.allclose(t.apply_vector([1, 0, 0]), [0, 1, 0])  # x -> y


def test_rotate_axis_is_normalised():
    a = xml_transform('<rotate axis="0,0,5" angle="90"/>')
    assert np.allclose(a.matrix, Transform.rotate([0, 0, 1], 90).matrix)
    # 120 degrees about the (unnormalised) diagonal cyclically permutes the axes x->y->z->x.
    b = xml_transform('<rotate axis="2 2 2" angle="120"/>')
    perm = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], float)
    assert np.allclose(b.matrix[:3, :3], perm, atol=1e-12)
    assert np.allclose(b.matrix[:3, 3], 0)


def test_matrix_is_row_major():
    t = xml_transform('<matrix value="1 0 0 7  0 2 0 8  0 0 1 9  0 0 0 1"/>')
    assert t.matrix[0, 3] == 7 and t.matrix[1, 3] == 8 and t.matrix[2, 3] == 9
    assert t.matrix[1, 1] == 2 and t.matrix[3, 0] == 0
    assert np.allclose(t.apply_point([1, 1, 1]), [8, 10, 10])


def test_lookat_columns():
    t = xml_transform('<lookat origin="0,0,5" target="0,0,0" up="0,1,1"/>')
    m = t.matrix
    assert np.allclose(m[:3, 0], [-1, 0, 0])  # left = normalize(cross(up, dir))
    assert np.allclose(m[:3, 1], [0, 1, 0])   # newUp = cross(dir, left)
    assert np.allclose(m[:3, 2], [0, 0, -1])  # dir
    assert np.allclose(m[:3, 3], [0, 0, 5])   # origin
    assert np.allclose(m[3], [0, 0, 0, 1])


def test_lookat_sideways():
    t = Transform.lookat([1, 2, 3], [4, 2, 3], [0, 0, 7])
    assert np.allclose(t.matrix[:3, :3], np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], float))
    assert np.allclose(t.apply_point([0, 0, 0]), [1, 2, 3])


def test_nori_camera_mirror_then_lookat():
    t = xml_transform('<scale value="-1,1,1"/><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/>')
    expected = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 5], [0, 0, 0, 1]], float)
    assert np.allclose(t.matrix, expected)


def test_composition_order_is_document_order():
    ts = xml_transform('<translate value="1,0,0"/><scale value="2"/>')  # translate first, then scale
    st = xml_transform('<scale value="2"/><translate value="1,0,0"/>')
    assert np.allclose(ts.matrix, [[2, 0, 0, 2], [0, 2, 0, 0], [0, 0, 2, 0], [0, 0, 0, 1]])
    assert np.allclose(st.matrix, [[2, 0, 0, 1], [0, 2, 0, 0], [0, 0, 2, 0], [0, 0, 0, 1]])
    assert np.allclose(ts.apply_point([0, 0, 0]), [2, 0, 0])
    assert np.allclose(st.apply_point([0, 0, 0]), [1, 0, 0])
    # The Python operator matches: a @ b applies b first.
    assert np.allclose((Transform.scale(2) @ Transform.translate([1, 0, 0])).matrix, ts.matrix)


def test_normals_use_inverse_transpose():
    t = Transform.scale([2, 1, 1])
    n = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)  # normal of the plane x + y = 0
    tangent = np.array([1.0, -1.0, 0.0])
    n2 = t.apply_normal(n)
    assert np.allclose(n2, np.array([1.0, 2.0, 0.0]) / np.sqrt(5))
    assert abs(np.dot(n2, t.apply_vector(tangent))) < 1e-12
    # Transforming the normal like a vector would be wrong here.
    v = t.apply_vector(n)
    assert abs(np.dot(v / np.linalg.norm(v), n2)) < 0.99


def test_batched_application_and_projective_divide():
    pts = np.array([[0, 0, 0], [1, 2, 3]], float)
    t = Transform.translate([1, 1, 1])
    assert np.allclose(t.apply_point(pts), [[1, 1, 1], [2, 3, 4]])
    normals = t.apply_normal(np.array([[0, 0, 2.0], [3.0, 0, 0]]))
    assert np.allclose(normals, [[0, 0, 1], [1, 0, 0]])
    proj = Transform([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 0]])  # w = z
    assert np.allclose(proj.apply_point([2, 4, 2]), [1, 2, 1])
    assert np.allclose(proj.apply_point([[2, 4, 2], [3, 3, 3]]), [[1, 2, 1], [1, 1, 1]])


def test_inverse():
    t = xml_transform('<scale value="1,2,3"/><rotate axis="1,1,0" angle="33"/><translate value="4,5,6"/>')
    assert np.allclose(t.inverse.matrix @ t.matrix, np.eye(4))
    assert np.allclose(t.inverse.inverse.matrix, t.matrix)
    m = Transform([[1, 2, 0, 1], [0, 1, 0, 2], [0, 0, 3, 0], [0, 0, 0, 1]])
    assert np.allclose(m.inverse.matrix, np.linalg.inv(m.matrix))


@pytest.mark.parametrize("ops, line, col, fragment", [
    ('<lookat origin="1,1,1" target="1,1,1" up="0,1,0"/>', 3, 1, "target equals origin"),
    ('  <rotate axis="0,0,0" angle="10"/>', 3, 3, "zero length"),
    ('<scale value="1,0,1"/>', 3, 1, "singular"),
    ('<matrix value="1 0 0 0 0 1 0 0 0 0 0 0 0 0 0 1"/>', 3, 1, "singular"),
])
def test_degenerate_ops_are_located(ops, line, col, fragment):
    with pytest.raises(SceneError) as e:
        xml_transform(ops)
    assert e.value.location.line == line and e.value.location.col == col
    assert fragment in str(e.value)


def test_parallel_lookat_is_nori_degenerate_frame():
    """Nori accepts an up parallel to the view: left = newUp = 0 (a warning, not an error)."""
    m = xml_transform('<lookat origin="0,0,0" target="0,5,0" up="0,1,0"/>').matrix
    np.testing.assert_array_equal(m[:3, :2], 0.0)
    np.testing.assert_allclose(m[:3, 2], [0, 1, 0])


@pytest.mark.parametrize("ops, expected", [
    ('<translate value="1,2"/>', "needs 3 numbers, got 2"),
    ('<scale value="1,2"/>', "needs 3 or 1 numbers, got 2"),
    ('<matrix value="1 2 3"/>', "needs 16 numbers, got 3"),
    ('<rotate axis="0,1,0" angle="1 2"/>', "needs 1 number, got 2"),
])
def test_op_component_counts(ops, expected):
    with pytest.raises(SceneError) as e:
        xml_transform(ops)
    assert expected in str(e.value)
    assert e.value.location.line == 3
