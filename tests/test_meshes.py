"""Mesh loading: OBJ semantics (Nori's), PLY via trimesh, and MeshData geometry helpers."""
from __future__ import annotations

import struct
import warnings

import numpy as np
import pytest

from clrender.errors import SceneError, SourceLocation
from clrender.shapes import objfile
from clrender.shapes.meshdata import MeshData
from clrender.shapes.objfile import load_obj
from clrender.shapes.plyfile import load_ply


def write(tmp_path, text, name="m.obj"):
    p = tmp_path / name
    p.write_text(text)
    return p


def load_both(path):
    """Load through the public API and through the careful parser alone; both must agree."""
    mesh = load_obj(path)
    slow = objfile._build(objfile._parse_slow(path.read_bytes(), str(path)))
    for a in ("positions", "normals", "uvs", "faces"):
        x, y = getattr(mesh, a), getattr(slow, a)
        assert (x is None) == (y is None), a
        if x is not None:
            np.testing.assert_array_equal(x, y, err_msg=a)
    return mesh


QUAD = """v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
"""


# ---------------------------------------------------------------------------------------------- OBJ


def test_quad_fan_triangulated(tmp_path):
    m = load_both(write(tmp_path, QUAD + "f 1 2 3 4\n"))
    np.testing.assert_array_equal(m.faces, [[0, 1, 2], [0, 2, 3]])
    np.testing.assert_array_equal(m.positions, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    assert m.normals is None and m.uvs is None


def test_pentagon_fan_and_vertex_order_of_first_use(tmp_path):
    text = QUAD + "v 0.5 1.5 0\nf 5 1 2 3 4\n"
    m = load_both(write(tmp_path, text))
    # Output vertices are numbered by first use: file vertex 5 becomes output vertex 0.
    np.testing.assert_array_equal(m.faces, [[0, 1, 2], [0, 2, 3], [0, 3, 4]])
    np.testing.assert_array_equal(m.positions[m.faces[2]], [[0.5, 1.5, 0], [1, 1, 0], [0, 1, 0]])


def test_negative_indices(tmp_path):
    text = "v 9 9 9\n" + QUAD + "f -4 -3 -2\nv 5 5 5\nf -1 -2 -3\n"
    m = load_both(write(tmp_path, text))
    tris = m.positions[m.faces]
    np.testing.assert_array_equal(tris[0], [[0, 0, 0], [1, 0, 0], [1, 1, 0]])
    # -1 in the second face is the vertex defined after the first face.
    np.testing.assert_array_equal(tris[1], [[5, 5, 5], [0, 1, 0], [1, 1, 0]])


def test_v_vt(tmp_path):
    text = QUAD + "vt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\n"
    m = load_both(write(tmp_path, text))
    assert m.normals is None
    np.testing.assert_array_equal(m.uvs[m.faces[0]], [[0, 0], [1, 0], [1, 1]])


def test_v_vn(tmp_path):
    text = QUAD + "vn 0 0 1\nvn 0 1 0\nf 1//1 2//2 3//1\n"
    m = load_both(write(tmp_path, text))
    assert m.uvs is None
    np.testing.assert_array_equal(m.normals[m.faces[0]], [[0, 0, 1], [0, 1, 0], [0, 0, 1]])


def test_v_vt_vn(tmp_path):
    text = QUAD + "vt 0.25 0.5\nvt 0.75 0.5\nvn 1 0 0\nvn 0 0 -1\nf 1/2/1 2/1/2 4/2/2\n"
    m = load_both(write(tmp_path, text))
    np.testing.assert_array_equal(m.positions[m.faces[0]], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(m.uvs[m.faces[0]], [[0.75, 0.5], [0.25, 0.5], [0.75, 0.5]])
    np.testing.assert_array_equal(m.normals[m.faces[0]], [[1, 0, 0], [0, 0, -1], [0, 0, -1]])


def test_missing_normals_are_none_even_if_vn_defined(tmp_path):
    m = load_both(write(tmp_path, QUAD + "vn 0 0 1\nf 1 2 3\n"))
    assert m.normals is None


def test_deindexing_splits_position_with_two_normals(tmp_path):
    text = QUAD + "vn 0 0 1\nvn 1 0 0\nf 1//1 2//1 3//1\nf 1//2 3//1 4//2\n"
    m = load_both(write(tmp_path, text))
    # (1,1),(2,1),(3,1) then (1,2),(4,2): position 1 appears twice; (3,1) is shared.
    assert m.positions.shape == (5, 3)
    np.testing.assert_array_equal(m.faces, [[0, 1, 2], [3, 2, 4]])
    np.testing.assert_array_equal(m.positions[0], m.positions[3])
    np.testing.assert_array_equal(m.normals[0], [0, 0, 1])
    np.testing.assert_array_equal(m.normals[3], [1, 0, 0])


def test_mixed_normals_get_face_normal(tmp_path):
    text = QUAD + "v 0 0 1\nvn 0 1 0\nf 1//1 2//1 3//1\nf 1 3 4\nf 1 5 2\n"
    m = load_both(write(tmp_path, text))
    np.testing.assert_array_equal(m.normals[m.faces[0]], np.tile([0, 1, 0], (3, 1)))
    np.testing.assert_allclose(m.normals[m.faces[1]], np.tile([0, 0, 1], (3, 1)))
    # File vertex 1 without vn is used by two triangles with different face normals: not shared.
    np.testing.assert_allclose(m.normals[m.faces[2]], np.tile([0, 1, 0], (3, 1)))
    assert m.faces[1, 0] != m.faces[2, 0]


def test_comments_groups_and_unknown_statements_ignored(tmp_path):
    text = ("# header\nmtllib x.mtl\no thing\n\ng grp\ns off\nusemtl red\n" + QUAD
            + "vp 0.1\nl 1 2\n   \n# f 1 2 9\nf 1 2 3 # trailing comment\n")
    m = load_both(write(tmp_path, text))
    np.testing.assert_array_equal(m.faces, [[0, 1, 2]])


def test_utf8_byte_order_mark_keeps_the_first_vertex(tmp_path):
    # Windows editors start a file with a BOM; it used to hide the first 'v', so 'f 1 2 3' took other vertices.
    p = tmp_path / "m.obj"
    p.write_bytes(b"\xef\xbb\xbf" + (QUAD + "f 1 2 3\n").encode())
    m = load_obj(p)
    np.testing.assert_array_equal(m.positions, [[0, 0, 0], [1, 0, 0], [1, 1, 0]])


def test_tabs_crlf_and_extra_vertex_numbers(tmp_path):
    text = "v\t0 0 0 1 0 0\r\nv 1 0 0 1 0 0\r\nv 0 1 0 1 0 0\r\n  f 1 2 3\r\n"
    m = load_both(write(tmp_path, text))
    np.testing.assert_array_equal(m.positions, [[0, 0, 0], [1, 0, 0], [0, 1, 0]])


def test_fast_and_slow_paths_agree_on_random_mesh(tmp_path):
    rng = np.random.default_rng(3)
    P = rng.random((50, 3)).round(4)
    lines = [f"v {x} {y} {z}" for x, y, z in P] + ["vn 0 0 1", "vn 0 1 0", "vt 0.5 0.5"]
    for _ in range(80):
        k = rng.integers(3, 6)
        idx = rng.choice(50, k, replace=False) + 1
        lines.append("f " + " ".join(f"{i}/1/{rng.integers(1, 3)}" for i in idx))
    path = write(tmp_path, "\n".join(lines) + "\n")
    assert objfile._parse_fast(path.read_bytes()) is not None
    m = load_both(path)
    assert m.faces.shape[0] == sum(len(ln.split()) - 3 for ln in lines if ln.startswith("f "))


def err(tmp_path, text):
    path = write(tmp_path, text)
    with pytest.raises(SceneError) as e:
        load_obj(path)
    return str(e.value), e.value


@pytest.mark.parametrize(
    "text, line, needle",
    [
        (QUAD + "v 1 2 x\nf 1 2 3\n", 5, "bad number 'x'"),
        (QUAD + "vn 1 2\nf 1 2 3\n", 5, "expects 3 numbers"),
        (QUAD + "f 1 2 3\nf 1 2 7\n", 6, "vertex index 7 is out of range"),
        (QUAD + "f 1 2 -9\n", 5, "out of range"),
        (QUAD + "vn 0 0 1\nf 1//1 2//1 3//2\n", 6, "normal index 2 is out of range"),
        (QUAD + "f 0 1 2\n", 5, "index 0"),
        (QUAD + "f 1 2\n", 5, "at least 3"),
        (QUAD + "f 1 2 3\nf 1 a 3\n", 6, "bad vertex index 'a'"),
        (QUAD + "f 1 2 3\nf 1///2 2 3\n", 6, "bad face corner"),
        (QUAD + "f 1 2 3\nf 1 2-3 4\n", 6, "'2-3'"),
    ],
)
# Warnings as errors: numpy 2.2's DeprecationWarning from np.fromstring at a bad token used to reach users.
@pytest.mark.filterwarnings("error")
def test_obj_errors_name_file_and_line(tmp_path, text, line, needle):
    msg, e = err(tmp_path, text)
    assert e.location.line == line
    assert msg.startswith(f"{tmp_path / 'm.obj'}:{line}:")
    assert needle in msg


def test_obj_without_faces(tmp_path):
    msg, e = err(tmp_path, QUAD)
    assert "no faces" in msg and str(tmp_path / "m.obj") in msg


def test_missing_obj_file_uses_scene_location(tmp_path):
    loc = SourceLocation("scene.xml", 12, 5)
    with pytest.raises(SceneError) as e:
        load_obj(tmp_path / "nope.obj", loc)
    assert e.value.location == loc
    assert str(e.value).startswith("scene.xml:12:5:")
    assert "nope.obj" in str(e.value)


# ---------------------------------------------------------------------------------------------- MeshData


def test_transformed_nonuniform_scale_uses_inverse_transpose():
    s = np.diag([2.0, 1.0, 0.5, 1.0])
    s[:3, 3] = [1, 2, 3]
    n = np.array([[1, 1, 0]], np.float32) / np.sqrt(2)
    m = MeshData(np.array([[1, 1, 1], [0, 0, 0], [1, 0, 0]]), np.repeat(n, 3, axis=0), None,
                 np.array([[0, 1, 2]]))
    t = m.transformed(s)
    np.testing.assert_allclose(t.positions[0], [3, 3, 3.5])
    # Hand computation: M^-T = diag(1/2, 1, 2); (1,1,0) -> (0.5, 1, 0), normalised.
    expected = np.array([0.5, 1.0, 0.0]) / np.sqrt(1.25)
    np.testing.assert_allclose(t.normals[0], expected, rtol=1e-6)
    # The normal stays perpendicular to transformed tangents (tangent (1,-1,0) -> (2,-1,0)).
    assert abs(np.dot(t.normals[0], [2, -1, 0])) < 1e-6


def test_transformed_mirror_keeps_inverse_transpose_normal_and_projective_divide():
    m = MeshData(np.array([[1, 2, 3], [0, 0, 0], [1, 0, 0]]), np.array([[0, 0, 1]] * 3), None,
                 np.array([[0, 1, 2]]))
    mirror = np.diag([1.0, 1.0, -1.0, 1.0])
    t = m.transformed(mirror)
    np.testing.assert_allclose(t.normals, [[0, 0, -1]] * 3)
    np.testing.assert_array_equal(t.faces, m.faces)
    proj = np.eye(4)
    proj[3, 3] = 2.0
    np.testing.assert_allclose(m.transformed(proj).positions[0], [0.5, 1, 1.5])


def test_drop_degenerate_counts():
    P = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [np.nan, 0, 0]])
    F = np.array([[0, 1, 2], [0, 0, 1], [0, 1, 3], [0, 1, 4], [2, 1, 0]])
    m, dropped = MeshData(P, None, None, F).drop_degenerate()
    assert dropped == 3  # repeated index, collinear, NaN vertex
    np.testing.assert_array_equal(m.faces, [[0, 1, 2], [2, 1, 0]])
    assert MeshData(P, None, None, F[:1]).drop_degenerate()[1] == 0


def test_areas_and_face_normals():
    m = MeshData(np.array([[0, 0, 0], [2, 0, 0], [0, 3, 0]]), None, None, np.array([[0, 1, 2], [0, 2, 1]]))
    np.testing.assert_allclose(m.triangle_areas(), [3, 3])
    np.testing.assert_allclose(m.face_normals(), [[0, 0, 1], [0, 0, -1]])
    assert m.triangle_areas().dtype == np.float64


# ---------------------------------------------------------------------------------------------- PLY

PLY_P = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 1.5, 0]], np.float32)
PLY_N = np.array([[0, 0, 1], [0, 1, 0], [1, 0, 0], [0, 0.6, 0.8], [0.8, 0, 0.6]], np.float32)
PLY_UV = np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.75]], np.float32)


def write_ply(path, faces, ascii, normals=False, uv_names=None, big_endian=False):
    props = ["x", "y", "z"] + (["nx", "ny", "nz"] if normals else []) + list(uv_names or [])
    fmt = "ascii" if ascii else ("binary_big_endian" if big_endian else "binary_little_endian")
    head = ["ply", f"format {fmt} 1.0", "comment test", f"element vertex {len(PLY_P)}"]
    head += [f"property float {p}" for p in props]
    head += [f"element face {len(faces)}", "property list uchar int vertex_indices", "end_header"]
    e = ">" if big_endian else "<"
    with open(path, "wb") as f:
        f.write(("\n".join(head) + "\n").encode())
        for i in range(len(PLY_P)):
            row = list(PLY_P[i]) + (list(PLY_N[i]) if normals else []) + (list(PLY_UV[i]) if uv_names else [])
            if ascii:
                f.write((" ".join(repr(float(x)) for x in row) + "\n").encode())
            else:
                f.write(struct.pack(f"{e}{len(row)}f", *row))
        for fc in faces:
            if ascii:
                f.write((" ".join(str(x) for x in [len(fc), *fc]) + "\n").encode())
            else:
                f.write(struct.pack(f"{e}B{len(fc)}i", len(fc), *fc))
    return path


@pytest.mark.parametrize("ascii", [True, False])
def test_ply_plain(tmp_path, ascii):
    m = load_ply(write_ply(tmp_path / "a.ply", [[0, 1, 2], [0, 2, 3]], ascii))
    np.testing.assert_array_equal(m.positions, PLY_P)
    np.testing.assert_array_equal(m.faces, [[0, 1, 2], [0, 2, 3]])
    assert m.normals is None and m.uvs is None


@pytest.mark.parametrize("ascii", [True, False])
@pytest.mark.parametrize("uv_names", [("s", "t"), ("u", "v"), ("texture_u", "texture_v")])
def test_ply_normals_and_uvs_kept(tmp_path, ascii, uv_names):
    m = load_ply(write_ply(tmp_path / "a.ply", [[0, 1, 2], [0, 2, 3], [3, 2, 4]], ascii, True, uv_names))
    # The file's normals are not face normals (which would all be +z): they must come through untouched.
    np.testing.assert_array_equal(m.normals, PLY_N)
    np.testing.assert_array_equal(m.uvs, PLY_UV)
    np.testing.assert_array_equal(m.positions, PLY_P)


@pytest.mark.parametrize("ascii", [True, False])
def test_ply_uniform_quads_fan(tmp_path, ascii):
    m = load_ply(write_ply(tmp_path / "q.ply", [[0, 1, 2, 3], [1, 2, 4, 3]], ascii))
    np.testing.assert_array_equal(m.faces, [[0, 1, 2], [0, 2, 3], [1, 2, 4], [1, 4, 3]])


@pytest.mark.parametrize("ascii, big_endian", [(True, False), (False, False), (False, True)])
def test_ply_mixed_polygons_fan(tmp_path, ascii, big_endian):
    path = write_ply(tmp_path / "p.ply", [[0, 1, 2], [0, 1, 2, 4, 3], [1, 2, 4, 3]], ascii, True,
                     ("u", "v"), big_endian)
    m = load_ply(path)
    np.testing.assert_array_equal(
        m.faces, [[0, 1, 2], [0, 1, 2], [0, 2, 4], [0, 4, 3], [1, 2, 4], [1, 4, 3]])
    np.testing.assert_array_equal(m.normals, PLY_N)
    np.testing.assert_array_equal(m.uvs, PLY_UV)
    np.testing.assert_array_equal(m.positions, PLY_P)


def test_ply_errors(tmp_path):
    loc = SourceLocation("scene.xml", 3, 1)
    with pytest.raises(SceneError) as e:
        load_ply(tmp_path / "missing.ply", loc)
    assert e.value.location == loc and "missing.ply" in str(e.value)
    bad = tmp_path / "bad.ply"
    bad.write_bytes(b"not a ply\n")
    with pytest.raises(SceneError):
        load_ply(bad)
    bad.write_bytes(b"version https://git-lfs.github.com/spec/v1\noid sha256:0\nsize 9\n")   # a repository's LFS file
    with pytest.raises(SceneError, match="not a PLY file .*; this is a Git LFS pointer, not the file"):
        load_ply(bad)
    with pytest.raises(SceneError, match="out of range"):
        load_ply(write_ply(tmp_path / "r.ply", [[0, 1, 9]], True))


def test_ply_bad_ascii_number_is_an_error_without_warnings(tmp_path):
    """numpy 2.2 (Python 3.10) warned twice on the way to a vaguer error; numpy 2.5 raises at once: the same now."""
    bad = tmp_path / "bad.ply"
    bad.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(SceneError, match="cannot parse PLY file: ValueError: string or file could not be read"):
            load_ply(bad)
    assert [str(w.message) for w in caught] == []


@pytest.mark.parametrize("big_endian", [False, True])
def test_binary_ply_with_scalar_face_properties(tmp_path, big_endian):
    """Face records with properties around the index list (a flag before it, a float after): read in one
    piece when every list has the first one's length, record by record when one differs; the same mesh."""
    e = ">" if big_endian else "<"
    fmt = "binary_big_endian" if big_endian else "binary_little_endian"

    def write(path, faces):
        head = ["ply", f"format {fmt} 1.0", f"element vertex {len(PLY_P)}", "property float x",
                "property float y", "property float z", f"element face {len(faces)}", "property uchar flag",
                "property list uchar uint vertex_indices", "property float quality", "end_header"]
        with open(path, "wb") as f:
            f.write(("\n".join(head) + "\n").encode())
            for p in PLY_P:
                f.write(struct.pack(f"{e}3f", *p))
            for k, fc in enumerate(faces):
                f.write(struct.pack(f"{e}BB{len(fc)}If", 7, len(fc), *fc, 0.5 * k))
        return path

    tris = load_ply(write(tmp_path / "t.ply", [[0, 1, 2], [0, 2, 3], [3, 2, 4]]))
    np.testing.assert_array_equal(tris.faces, [[0, 1, 2], [0, 2, 3], [3, 2, 4]])
    np.testing.assert_array_equal(tris.positions, PLY_P)
    mixed = load_ply(write(tmp_path / "m.ply", [[0, 1, 2], [0, 2, 3, 4]]))
    np.testing.assert_array_equal(mixed.faces, [[0, 1, 2], [0, 2, 3], [0, 3, 4]])
    truncated = tmp_path / "cut.ply"
    truncated.write_bytes((tmp_path / "t.ply").read_bytes()[:-6])
    with pytest.raises(SceneError, match="truncated|past the end"):
        load_ply(truncated)


def test_binary_ply_does_not_import_trimesh(tmp_path):
    """Importing trimesh costs about 0.75 s (scipy.spatial): a binary PLY (what large meshes come as) is read
    without it, so it stays out of the first image's latency."""
    import subprocess
    import sys

    path = write_ply(tmp_path / "b.ply", [[0, 1, 2], [0, 2, 3]], False, True)
    code = ("import sys; from clrender.shapes.plyfile import load_ply; m = load_ply(sys.argv[1]); "
            "assert m.faces.shape == (2, 3); print('trimesh' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_a_missing_mesh_quotes_its_note(tmp_path):
    """NAME.missing beside a missing mesh NAME (how to get it) is quoted in the error; without one, or for a mesh that
    exists but cannot be read, nothing is added."""
    from clrender.errors import SceneError
    from clrender.shapes.meshfile import read_mesh_bytes

    (tmp_path / "m.ply.missing").write_text("made by\n   ./make-meshes.sh\n")
    with pytest.raises(SceneError, match=r"No such file or directory \(m.ply.missing: made by ./make-meshes.sh\)"):
        read_mesh_bytes(tmp_path / "m.ply", "PLY", None)
    with pytest.raises(SceneError, match=r"No such file or directory$"):
        read_mesh_bytes(tmp_path / "n.ply", "PLY", None)
    (tmp_path / "d.ply").mkdir()
    (tmp_path / "d.ply.missing").write_text("not quoted")
    with pytest.raises(SceneError, match=r"it is a folder, not a file$"):
        read_mesh_bytes(tmp_path / "d.ply", "PLY", None)
