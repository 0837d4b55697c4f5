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


def _load_build():
    spec = importlib.util.spec_from_file_location("scenes_build", SCENES / "build.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _listing(root):
    out = set()
    for p in Path(root).rglob("*"):
        rel = p.relative_to(root)
        if p.is_dir() or "__pycache__" in rel.parts or rel.as_posix() in NOT_GENERATED:
            continue
        out.add(rel.as_posix())
    return out


@pytest.fixture(scope="module")
def regenerated(tmp_path_factory):
    out = tmp_path_factory.mktemp("scenes")
    subprocess.run([sys.executable, str(SCENES / "build.py"), "--out", str(out)], check=True,
                   capture_output=True)
    return out


def test_regeneration_is_byte_identical(regenerated):
    generated = _listing(regenerated)
    committed = _listing(SCENES)
    assert generated, "build.py wrote nothing"
    missing = sorted(committed - generated)
    assert not missing, "committed files that build.py no longer generates: %s" % missing
    extra = sorted(generated - committed)
    assert not extra, "generated files not committed under scenes/: %s" % extra
    differ = [f for f in sorted(generated) if (regenerated / f).read_bytes() != (SCENES / f).read_bytes()]
    assert not differ, "regenerated files differ from the committed ones: %s" % differ


def test_regeneration_is_deterministic(tmp_path):
    """Two in-process builds give the same bytes (no RNG state or ordering leaks)."""
    build = _load_build()
    a, b = tmp_path / "a", tmp_path / "b"
    files = build.build(a)
    assert files == build.build(b)
    small = [f for f in files if not f.endswith(".ply")]
    assert all((a / f).read_bytes() == (b / f).read_bytes() for f in small)


def test_sanity_checks_on_committed_scenes():
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
        assert len(root.findall("integrator")) == 1 and len(root.findall("camera")) == 1


def test_large_ply_layout():
    p = SCENES / "largemesh" / "meshes" / "blob_1m.ply"
    data = p.read_bytes()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").split("\n")
    assert header[1] == "format binary_little_endian 1.0"
    nv = int(next(l for l in header if l.startswith("element vertex")).split()[-1])
    nf = int(next(l for l in header if l.startswith("element face")).split()[-1])
    assert nf >= 1_000_000
    assert len(data) == end + 24 * nv + 13 * nf
    vert = np.frombuffer(data, dtype=[("p", "<f4", (3,)), ("n", "<f4", (3,))], count=nv, offset=end)
    face = np.frombuffer(data, dtype=[("c", "u1"), ("i", "<i4", (3,))], count=nf, offset=end + 24 * nv)
    assert np.all(face["c"] == 3) and face["i"].min() == 0 and face["i"].max() == nv - 1
    assert np.allclose(np.linalg.norm(vert["n"], axis=1), 1, atol=1e-5)
    # normals point outward (the blob is star-shaped about its centre)
    assert np.all(np.einsum("ij,ij->i", vert["n"], vert["p"]) > 0)


def test_total_size_budget():
    total = sum((SCENES / f).stat().st_size for f in _listing(SCENES))
    assert total < 30e6, total
