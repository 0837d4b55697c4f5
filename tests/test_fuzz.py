"""Fuzz tests (hypothesis) of the XML parser and scene loader, the OBJ and PLY readers and the command line.

The property is always the same: an input is either accepted or refused with a clrender error (a located
message) -- never another exception, never a hang (each example runs under an alarm). The default run is
short; for a long run set CLRENDER_FUZZ_EXAMPLES (e.g. 20000) and give pytest `-p no:cacheprovider`.
"""
import contextlib
import os
import re
import signal
import struct

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from clrender.errors import ClrenderError, SceneError

EXAMPLES = int(os.environ.get("CLRENDER_FUZZ_EXAMPLES", "40"))
fuzz = settings(max_examples=EXAMPLES, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                       HealthCheck.data_too_large])
HANG_SECONDS = 60


@contextlib.contextmanager
def no_hang(seconds=HANG_SECONDS):
    def alarm(signum, frame):
        raise AssertionError(f"hung for more than {seconds} s")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


VALID_SCENE = """<?xml version="1.0"?>
<scene>
  <default name="r" value="0.5"/>
  <integrator type="path_mis"><integer name="maxDepth" value="4"/></integrator>
  <sampler type="independent"><integer name="sampleCount" value="2"/></sampler>
  <camera type="perspective">
    <integer name="width" value="8"/><integer name="height" value="6"/><float name="fov" value="40"/>
    <transform name="toWorld"><scale value="-1,1,1"/><lookat origin="0,1,4" target="0,0,0" up="0,1,0"/></transform>
    <rfilter type="gaussian"><float name="radius" value="2"/></rfilter>
  </camera>
  <mesh type="sphere"><point name="center" value="0, 0, 0"/><float name="radius" value="$r"/>
    <bsdf type="microfacet"><float name="alpha" value="0.2"/></bsdf></mesh>
  <mesh type="sphere"><float name="radius" value="0.2"/><point name="center" value="1,1,1"/>
    <emitter type="area"><color name="radiance" value="4, 4, 4"/></emitter></mesh>
  <emitter type="point"><point name="position" value="0,3,0"/><color name="power" value="10"/></emitter>
  <mesh type="obj"><string name="filename" value="ground.obj"/>
    <transform name="toWorld"><rotate axis="1,0,0" angle="-90"/><translate value="0,-1,0"/></transform>
    <bsdf type="dielectric"/></mesh>
</scene>
"""
TOKENS = ["<", ">", "/>", "</", '"', "'", "=", " ", "\n", "&amp;", "&#0;", "&lt;", "<!--", "-->", "<?xml ?>",
          "<![CDATA[", "]]>", "scene", "mesh", "bsdf", "emitter", "camera", "integrator", "sampler", "rfilter",
          "transform", "float", "integer", "point", "color", "string", "boolean", "vector", "translate", "rotate",
          "scale", "matrix", "lookat", "default", "type", "name", "value", "filename", "radius", "center",
          "width", "height", "nan", "inf", "-1", "0", "1e999", "99999999999999999999", "1,2,3", "$r", "$", "é",
          "\x00", "\udcff", "diffuse", "sphere", "obj", "ply", "normals", "path_mis", "toWorld"]


def _load(text: bytes, tmp_path):
    from clrender.loader import load_scene

    (tmp_path / "ground.obj").write_text("v -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\nf 1 2 3 4\n")
    p = tmp_path / "s.xml"
    p.write_bytes(text)
    try:
        with no_hang():
            load_scene(p)
    except SceneError as e:
        assert str(p) in str(e) or "ground.obj" in str(e), str(e)  # every scene error is located


@st.composite
def mutated(draw, base: bytes, alphabet=None):
    """`base` with a few random edits: deletions, insertions of tokens or bytes, replacements, a cut."""
    data = bytearray(base)
    for _ in range(draw(st.integers(1, 6))):
        op = draw(st.sampled_from(["delete", "insert", "token", "replace", "truncate", "duplicate"]))
        i = draw(st.integers(0, len(data)))
        if op == "delete":
            del data[i:i + draw(st.integers(1, 20))]
        elif op == "insert":
            data[i:i] = draw(st.binary(min_size=1, max_size=8))
        elif op == "token" and alphabet:
            data[i:i] = draw(st.sampled_from(alphabet)).encode("utf-8", "surrogateescape")
        elif op == "replace" and i < len(data):
            data[i] = draw(st.integers(0, 255))
        elif op == "truncate":
            del data[i:]
        elif op == "duplicate":
            j = draw(st.integers(i, min(len(data), i + 200)))
            data[j:j] = data[i:j]
    return bytes(data)


@fuzz
@given(data=mutated(VALID_SCENE.encode(), TOKENS))
def test_fuzz_scene_mutations(tmp_path, data):
    _load(data, tmp_path)


@fuzz
@given(parts=st.lists(st.sampled_from(TOKENS), max_size=60))
def test_fuzz_scene_from_tokens(tmp_path, parts):
    _load("".join(parts).encode("utf-8", "surrogateescape"), tmp_path)


@fuzz
@given(data=st.binary(max_size=300))
def test_fuzz_scene_random_bytes(tmp_path, data):
    _load(data, tmp_path)


VALID_MITSUBA = """<?xml version="1.0"?>
<scene version="3.0.0">
  <default name="spp" value="2"/>
  <integrator type="path"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/><string name="fov_axis" value="x"/>
    <transform name="to_world"><lookat origin="0,1,4" target="0,0,0" up="0,1,0"/></transform>
    <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/>
      <rfilter type="tent"><float name="radius" value="1"/></rfilter></film>
  </sensor>
  <bsdf type="roughconductor" id="metal"><string name="material" value="Au"/><float name="alpha" value="0.2"/></bsdf>
  <shape type="sphere"><point name="center" value="0, 0, 0"/><float name="radius" value="0.5"/><ref id="metal"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="4"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"><texture type="checkerboard" name="reflectance"><rgb name="color0" value="0.2"/>
      <spectrum name="color1" value="400:0.5, 700:0.8"/></texture></bsdf></shape>
  <shape type="obj"><string name="filename" value="ground.obj"/><boolean name="face_normals" value="true"/>
    <bsdf type="dielectric"><string name="int_ior" value="bk7"/></bsdf>
    <emitter type="area"><rgb name="radiance" value="4, 4, 4"/></emitter></shape>
  <emitter type="point"><point name="position" value="0,3,0"/><rgb name="intensity" value="10"/></emitter>
  <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter>
</scene>
"""
MITSUBA_TOKENS = TOKENS + ["shape", "sensor", "film", "hdrfilm", "rgb", "spectrum", "ref", "id", "include",
                           "to_world", "sample_count", "version", '"3.0.0"', "roughconductor", "alpha", "texture",
                           "checkerboard", "x", "angle", "400:0.5", "1e39", "3e38", "-1e13", "1e20", "rectangle"]


@fuzz
@given(data=mutated(VALID_MITSUBA.encode(), MITSUBA_TOKENS))
@example(data=VALID_MITSUBA.replace('value="0.5"/><ref', 'value="1e39"/><ref').encode())  # was an out-of-memory
def test_fuzz_mitsuba_scene_mutations(tmp_path, data):
    _load(data, tmp_path)


# ---- hostile values in valid scenes: each attribute value replaced by an extreme one -------------------------------
_VALUE = re.compile(r'(?:value|x|angle|origin|target|up)="([^"$]*)"')
HOSTILE_VALUES = ["0", "-1", "1e30", "-1e30", "1e-30", "3e38", "1e39", "1e13", "1e20", "nan", "", "1,0", "0,0,0", "-0",
                  "2147483648", "99999999999", "x"]
VALUE_SITES = [(name, i) for name, text in (("nori", VALID_SCENE), ("mitsuba", VALID_MITSUBA))
               for i in range(len(_VALUE.findall(text)))]


def _with_value(name: str, i: int, value: str) -> str:
    text = VALID_SCENE if name == "nori" else VALID_MITSUBA
    a, b = list(_VALUE.finditer(text))[i].span(1)
    return text[:a] + value + text[b:]


@fuzz
@given(site=st.sampled_from(VALUE_SITES), value=st.sampled_from(HOSTILE_VALUES))
@example(site=("nori", 1), value="99999999999")  # maxDepth: was an OverflowError traceback while packing
@example(site=("nori", 10), value="1e-30")        # the filter's radius: numpy warnings, then a black image
@example(site=("mitsuba", 24), value="3e38")      # a point light's intensity: its power overflowed float32
def test_fuzz_hostile_values_load_and_pack(tmp_path, site, value):
    """Loaded and packed (tables and BVH), an extreme value is accepted or refused with a clrender error: never
    another exception, never numpy's RuntimeWarnings on the user's terminal."""
    import warnings

    from clrender.loader import load_scene
    from clrender.pack import pack_scene

    (tmp_path / "ground.obj").write_text("v -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\nf 1 2 3 4\n")
    p = tmp_path / "s.xml"
    p.write_text(_with_value(*site, value))
    with warnings.catch_warnings(), no_hang():
        warnings.simplefilter("error", RuntimeWarning)
        try:
            pack_scene(load_scene(p))
        except SceneError as e:
            assert str(p) in str(e) or "ground.obj" in str(e), str(e)


# ---- OBJ --------------------------------------------------------------------------------------------------------
NUM = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=32).map(repr),
                st.integers(-10**25, 10**25).map(str), st.sampled_from(["x", "", "1e999", "-0", "nan", "1/2"]))
IDX = st.one_of(st.integers(-12, 12).map(str), st.integers(-10**25, 10**25).map(str),
                st.sampled_from(["", "x", "0", "1.5"]))
CORNER = st.one_of(IDX, st.tuples(IDX, IDX).map("/".join), st.tuples(IDX, IDX, IDX).map("/".join),
                   st.tuples(IDX, IDX).map(lambda t: f"{t[0]}//{t[1]}"))
OBJ_LINE = st.one_of(
    st.lists(NUM, min_size=0, max_size=4).map(lambda v: "v " + " ".join(v)),
    st.lists(NUM, min_size=0, max_size=3).map(lambda v: "vt " + " ".join(v)),
    st.lists(NUM, min_size=0, max_size=4).map(lambda v: "vn " + " ".join(v)),
    st.lists(CORNER, min_size=0, max_size=6).map(lambda v: "f " + " ".join(v)),
    st.sampled_from(["# comment", "", "o thing", "g group", "s 1", "usemtl m", "\tv 0 0 0", "  f 1 2 3",
                     "v 0 0 0 # c", "f 1 2 3 # c", "l 1 2", "vp 0.5"]),
    st.text(max_size=20),
)


def _check_mesh(loader, data: bytes, tmp_path, name):
    p = tmp_path / name
    p.write_bytes(data)
    try:
        with no_hang():
            mesh = loader(str(p))
    except SceneError as e:
        assert name in str(e), str(e)
        return
    import numpy as np

    assert mesh.faces.size and mesh.faces.min() >= 0 and mesh.faces.max() < mesh.vertex_count
    assert np.isfinite(mesh.positions).all()


@fuzz
@given(lines=st.lists(OBJ_LINE, max_size=30))
def test_fuzz_obj_statements(tmp_path, lines):
    from clrender.shapes.objfile import load_obj

    _check_mesh(load_obj, "\n".join(lines).encode("utf-8", "surrogateescape"), tmp_path, "m.obj")


GOOD_OBJ = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/1/1\nf -4 -3 -2\n"


@fuzz
@given(data=mutated(GOOD_OBJ, ["v ", "f ", "vn ", "vt ", "/", "//", "-", "99999999999999999999", "nan", "\n"]))
def test_fuzz_obj_mutations(tmp_path, data):
    from clrender.shapes.objfile import load_obj

    _check_mesh(load_obj, data, tmp_path, "m.obj")


# ---- PLY --------------------------------------------------------------------------------------------------------
def _ply(fmt, nv, nf, body, props=("float x", "float y", "float z"), list_types=("uchar", "int")):
    head = f"ply\nformat {fmt} 1.0\nelement vertex {nv}\n"
    head += "".join(f"property {p}\n" for p in props)
    head += f"element face {nf}\nproperty list {list_types[0]} {list_types[1]} vertex_indices\nend_header\n"
    return head.encode() + body


GOOD_BIN = _ply("binary_little_endian", 4, 2,
                b"".join(struct.pack("<3f", *p) for p in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)])
                + struct.pack("<B3i", 3, 0, 1, 2) + struct.pack("<B4i", 4, 0, 1, 2, 3))
GOOD_ASCII = _ply("ascii", 4, 2, b"0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n4 0 1 2 3\n")
PLY_TOKENS = ["element", "property", "list", "float", "double", "uchar", "int", "vertex", "face", "end_header",
              "format", "ascii", "binary_big_endian", "2000000000", "-1", "\n", " ", "nx", "u", "comment"]


@fuzz
@given(data=st.one_of(mutated(GOOD_BIN, PLY_TOKENS), mutated(GOOD_ASCII, PLY_TOKENS)))
@example(data=GOOD_ASCII.replace(b"end_header\n0 0 0", b"end_header\n 0 0"))  # found by a long run: ragged rows
def test_fuzz_ply_mutations(tmp_path, data):
    from clrender.shapes.plyfile import load_ply

    _check_mesh(load_ply, data, tmp_path, "m.ply")


@fuzz
@given(fmt=st.sampled_from(["ascii", "binary_little_endian", "binary_big_endian"]),
       nv=st.integers(-2, 3 * 10**9), nf=st.integers(-2, 3 * 10**9), body=st.binary(max_size=200),
       props=st.lists(st.sampled_from(["float x", "float y", "float z", "double x", "uchar nx", "float u",
                                       "float v", "int y", "list uchar int z"]), max_size=6),
       list_types=st.tuples(st.sampled_from(["uchar", "int", "float", "uint"]),
                            st.sampled_from(["int", "uint", "short", "double"])))
def test_fuzz_ply_headers(tmp_path, fmt, nv, nf, body, props, list_types):
    from clrender.shapes.plyfile import load_ply

    _check_mesh(load_ply, _ply(fmt, nv, nf, body, props, list_types), tmp_path, "m.ply")


# ---- command line -----------------------------------------------------------------------------------------------
OPTION_VALUES = st.sampled_from(["nan", "inf", "-inf", "-1", "0", "1", "2", "0.3", "1e999", "x", "", "4294967296",
                                 "99999999999999999999", "-0", "0x10", "NAME=1", "=", "cpu", "gpu", "99", "é"])
OPTION = st.one_of(
    st.tuples(st.sampled_from(["--spp", "--seed", "--time-limit", "--device", "-D", "--define"]), OPTION_VALUES),
    st.tuples(st.sampled_from(["-q", "--progress", "--quiet", "--bogus", "-x", "--"])),
    st.tuples(st.just("-o"), st.sampled_from(["out.exr", "out", "out.jpg", "out.png", "sub/", "/proc/x.exr",
                                               "", ".", "s.xml", "ground.obj/x.exr", "OUT.EXR"])),
)


@fuzz
@given(options=st.lists(OPTION, max_size=5), scene=st.sampled_from(["s.xml", "none.xml", ".", "ground.obj"]))
def test_fuzz_command_line(tmp_path, capsys, options, scene):
    from clrender.cli import main

    (tmp_path / "ground.obj").write_text("v -5 -5 0\nv 5 -5 0\nv 5 5 0\nv -5 5 0\nf 1 2 3 4\n")
    (tmp_path / "s.xml").write_text(VALID_SCENE.replace('value="2"/></sampler>', 'value="1"/></sampler>'))
    argv = ["render", str(tmp_path / scene)]
    for opt in options:
        argv += [str(tmp_path / a) if opt[0] == "-o" and a and not a.startswith("/") and i else a
                 for i, a in enumerate(opt)]
    if not any(a in ("--spp",) for a in argv):
        argv += ["--spp", "1"]
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        with no_hang():
            code = main(argv)
    except SystemExit as e:  # argparse
        code = e.code
    finally:
        os.chdir(cwd)
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert code in (0, 2, 130), (code, err)
    if code == 2:
        assert err.strip()


def test_fuzz_checks_can_fail(tmp_path):
    # The property really tests something: an exception that is not a clrender error escapes _check_mesh.
    def broken_loader(path):
        raise ValueError("a reader bug")

    with pytest.raises(ValueError):
        _check_mesh(broken_loader, b"v 0 0 0", tmp_path, "m.obj")
    assert issubclass(SceneError, ClrenderError)
