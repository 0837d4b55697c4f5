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


def test_merge_denoises_the_merged_image(tmp_path):
    """Parts rendered with the albedo and normal AOVs, merged with --denoise: the denoised file beside the merged one,
    equal to denoising the single render of the same samples (the same guides: merge adds the parts' sums)."""
    pytest.importorskip("pyoidn", reason="the denoise extra (pyoidn) is not installed")
    from clrender.cli import main

    xml = str(small_cornell_xml(tmp_path, 16))
    common = ["-q", "--seed", "4", "--aov", "albedo,normal"]
    for i, rng in enumerate(("0:2", "2:2")):
        assert main(["render", xml, "--sample-range", rng, "-o", str(tmp_path / f"p{i}.exr"), *common]) == 0
    assert main(["merge", str(tmp_path / "p0.exr"), str(tmp_path / "p1.exr"), "-o", str(tmp_path / "m.exr"),
                 "--denoise"]) == 0
    assert main(["render", xml, "--spp", "4", "-o", str(tmp_path / "w.exr"), "--denoise", *common]) == 0
    merged, _ = read_exr(tmp_path / "m.denoised.exr")
    whole, _ = read_exr(tmp_path / "w.denoised.exr")
    np.testing.assert_allclose(merged, whole, rtol=1e-3, atol=1e-4)
