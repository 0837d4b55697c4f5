"""Denoising (clrender/denoise.py, Film.denoised, `render --denoise`) with Open Image Denoise.

- A noisy render of the Cornell box, denoised with its albedo and normal guides, is closer to a long render than the
  raw image (relMSE several times lower) and keeps its mean brightness.
- `--denoise` writes NAME.denoised.exr and .png beside the raw image, which stays as rendered.
- Without the `denoise` extra: a clear error saying what to install, before rendering (exit status 2).
"""
import sys
from pathlib import Path

import numpy as np
import pytest

import clrender
from clrender.errors import ClrenderError
from clrender.film import read_exr
from clrender.renderer import Renderer

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def relmse(img, ref):
    return float(np.mean((img - ref) ** 2 / (ref * ref + 1e-2)))


def small_cornell_xml(tmp_path, size=32):
    d = tmp_path / "cornell"
    d.mkdir()
    (d / "meshes").symlink_to(SCENES / "cornell" / "meshes")
    xml = d / "small.xml"
    xml.write_text((SCENES / "cornell" / "cornell_path_mis.xml").read_text().replace('"256"', f'"{size}"'))
    return xml


def test_denoised_is_closer_to_the_reference(tmp_path):
    pytest.importorskip("pyoidn", reason="the denoise extra (pyoidn) is not installed")
    scene = clrender.load_scene(small_cornell_xml(tmp_path))
    r = Renderer(scene, feature_aovs=True)
    noisy = r.render(spp=4, seed=1)
    ref = Renderer(scene).render(spp=512, seed=2).image
    raw_err, den = relmse(noisy.image, ref), noisy.denoised()
    den_err = relmse(den, ref)
    assert den.shape == noisy.image.shape and np.isfinite(den).all()
    assert den_err < raw_err / 3, (raw_err, den_err)
    np.testing.assert_allclose(den.mean(axis=(0, 1)), ref.mean(axis=(0, 1)), rtol=0.1)


def test_command_line_writes_beside_the_raw_image(tmp_path):
    pytest.importorskip("pyoidn", reason="the denoise extra (pyoidn) is not installed")
    from clrender.cli import main

    out = tmp_path / "o.exr"
    assert main(["render", str(small_cornell_xml(tmp_path, 16)), "-o", str(out), "-q", "--spp", "2",
                 "--denoise"]) == 0
    raw, _ = read_exr(out)
    den, header = read_exr(tmp_path / "o.denoised.exr")
    assert (tmp_path / "o.png").is_file() and (tmp_path / "o.denoised.png").is_file()
    assert raw.shape == den.shape and not np.array_equal(raw, den)
    assert float(header["clrender.denoise_seconds"]) > 0


def test_missing_extra_says_what_to_install(tmp_path, monkeypatch, capsys):
    from clrender.cli import main
    from clrender.denoise import denoise

    monkeypatch.setitem(sys.modules, "pyoidn", None)   # as if not installed
    with pytest.raises(ClrenderError, match=r'pip install "clrender\[denoise\]"'):
        denoise(np.zeros((2, 2, 3), np.float32))
    out = tmp_path / "o.exr"
    assert main(["render", str(small_cornell_xml(tmp_path, 8)), "-o", str(out), "-q", "--spp", "1",
                 "--denoise"]) == 2
    assert 'pip install "clrender[denoise]"' in capsys.readouterr().err
    assert not out.exists(), "refused before rendering"
