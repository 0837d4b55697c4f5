"""scenes/build.py regenerates every committed scene file byte-for-byte, and the scenes are sane."""
import importlib.util
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

SCENES = Path(__file__).resolve().parents[1] / "scenes"
NOT_GENERATED = {"build.py", "README.md"}
GENERATED_SUFFIXES = {".xml", ".obj", ".ply", ".missing"}
LARGE = {"largemesh/meshes/blob_1m.ply", "largemesh/meshes/blob_100k.ply"}  # generated on demand, not in git


def _load_build():
    spec = importlib.util.spec_from_file_location("scenes_build", SCENES / "build.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _listing(root):
    out = set()
    for p in Path(root).rglob("*"):
        rel = p.relative_to(root)
        if p.is_dir() or p.suffix not in GENERATED_SUFFIXES or rel.as_posix() in NOT_GENERATED:
            continue
        out.add(rel.as_posix())
    return out


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory):
    out = tmp_path_factory.mktemp("scenes")
    subprocess.run([sys.executable, str(SCENES / "build.py"), "--out", str(out)], check=True,
                   capture_output=True)
    return out


@pytest.fixture(scope="module")
def large_meshes():
    return _load_build().ensure_large_meshes(SCENES)


def test_regeneration_is_byte_identical(regenerated, large_meshes):
    generated = _listing(regenerated)
    committed = _listing(SCENES)
    assert generated, "build.py wrote nothing"
    missing = sorted(committed - generated)
    assert not missing, "committed files that build.py no longer generates: %s" % missing
    extra = sorted(generated - committed)
    assert not extra, "generated files not committed under scenes/: %s" % extra
    differ = [f for f in sorted(generated - LARGE) if (regenerated / f).read_bytes() != (SCENES / f).read_bytes()]
    assert not differ, "regenerated files differ from the committed ones: %s" % differ


def _ply_arrays(path):
    data = Path(path).read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").split("\n")
    nv = int(next(l for l in header if l.startswith("element vertex")).split()[-1])
    nf = int(next(l for l in header if l.startswith("element face")).split()[-1])
    assert len(data) == end + 24 * nv + 13 * nf
    vert = np.frombuffer(data, dtype=[("p", "<f4", (3,)), ("n", "<f4", (3,))], count=nv, offset=end)
    face = np.frombuffer(data, dtype=[("c", "u1"), ("i", "<i4", (3,))], count=nf, offset=end + 24 * nv)
    return header, vert, face


@pytest.mark.parametrize("name", sorted(LARGE))
def test_large_meshes_agree_to_float_rounding(regenerated, large_meshes, name):
    """numpy's vectorised sin may differ in a last bit between CPUs: same topology, positions and normals
    within a few float32 ulps."""
    ha, va, fa = _ply_arrays(regenerated / name)
    hb, vb, fb = _ply_arrays(SCENES / name)
    assert ha == hb
    assert np.array_equal(fa, fb)
    np.testing.assert_allclose(va["p"], vb["p"], rtol=0, atol=4e-7)
    np.testing.assert_allclose(va["n"], vb["n"], rtol=0, atol=4e-7)


def test_stray_files_beside_scenes_are_ignored(tmp_path):
    (tmp_path / "cornell").mkdir()
    (tmp_path / "cornell" / "cornell_path_mis.xml").write_text("<scene/>")
    (tmp_path / "cornell" / "cornell_path_mis.exr").write_bytes(b"x")
    (tmp_path / "cornell" / "cornell_path_mis.png").write_bytes(b"x")
    assert _listing(tmp_path) == {"cornell/cornell_path_mis.xml"}


def test_regeneration_is_deterministic(tmp_path):
    """Two in-process builds give the same bytes (no RNG state or ordering leaks)."""
    build = _load_build()
    a, b = tmp_path / "a", tmp_path / "b"
    files = build.build(a)
    assert files == build.build(b)
    small = [f for f in files if not f.endswith(".ply")]
    assert all((a / f).read_bytes() == (b / f).read_bytes() for f in small)


def test_sanity_checks_on_committed_scenes(large_meshes):
    assert _load_build().sanity_checks(SCENES)


def test_every_xml_parses_and_has_a_description():
    xmls = sorted(SCENES.rglob("*.xml"))
    assert len(xmls) >= 30
    for p in xmls:
        text = p.read_text(encoding="utf-8")
        assert text.startswith('<?xml version="1.0" encoding="utf-8"?>\n<!--'), p
        assert "Correct image" in text or "expect" in text, p
        root = ET.parse(p).getroot()
        assert root.tag == "scene"
        camera = "sensor" if root.get("version") else "camera"     # a Mitsuba 3 file, or a Nori one
        assert len(root.findall("integrator")) == 1 and len(root.findall(camera)) == 1


def test_large_ply_layout(large_meshes):
    header, vert, face = _ply_arrays(SCENES / "largemesh" / "meshes" / "blob_1m.ply")
    assert header[1] == "format binary_little_endian 1.0"
    nv, nf = len(vert), len(face)
    assert nf >= 1_000_000
    assert np.all(face["c"] == 3) and face["i"].min() == 0 and face["i"].max() == nv - 1
    assert np.allclose(np.linalg.norm(vert["n"], axis=1), 1, atol=1e-5)
    # normals point outward (the blob is star-shaped about its centre)
    assert np.all(np.einsum("ij,ij->i", vert["n"], vert["p"]) > 0)


def test_total_size_budget():
    """What is committed stays small; the large meshes are generated."""
    total = sum((SCENES / f).stat().st_size for f in _listing(SCENES) - LARGE)
    assert total < 2e6, total


def test_large_meshes_are_regenerated_only_when_missing_or_incomplete(tmp_path):
    build = _load_build()
    p1, p2 = build.ensure_large_meshes(tmp_path)
    t = p1.stat().st_mtime_ns
    build.ensure_large_meshes(tmp_path)
    assert p1.stat().st_mtime_ns == t  # cached
    with open(p1, "r+b") as f:       # a truncated file (an interrupted generation) is made again
        f.truncate(1000)
    build.ensure_large_meshes(tmp_path)
    assert p1.stat().st_size > 20e6


@pytest.mark.parametrize("scene", ["largemesh_normals.xml", "mesh100k_normals.xml"])
def test_a_missing_large_mesh_names_the_command_that_makes_it(tmp_path, capsys, scene):
    """From a fresh clone (no PLY: it is generated on demand) `clrender render` said only "No such file"; the
    .missing note build.py writes beside the PLY's place is quoted in the error."""
    import shutil

    from clrender.cli import main

    shutil.copytree(SCENES / "largemesh", tmp_path / "largemesh", ignore=shutil.ignore_patterns("blob_*.ply"))
    assert main(["render", str(tmp_path / "largemesh" / scene), "-q", "--spp", "1"]) == 2
    err = capsys.readouterr().err
    assert f"{scene}:32:" in err or f"{scene}:33:" in err, err
    assert "No such file or directory (blob_" in err and "python scenes/build.py --large-meshes" in err, err
