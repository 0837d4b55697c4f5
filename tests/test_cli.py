"""The command line: clear errors (file:line, non-zero exit, no traceback) and Ctrl-C keeping the partial image."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from clrender.cli import main
from clrender.film import read_exr

GOOD = """<scene>
  <integrator type="ao"/>
  <camera type="perspective"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>
    <transform name="toWorld"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/></transform></camera>
  <mesh type="sphere"><float name="radius" value="1"/></mesh>
  <mesh type="obj"><string name="filename" value="{mesh}"/></mesh>
</scene>
"""
QUAD = "v -2 -2 -1\nv 2 -2 -1\nv 2 2 -1\nv -2 2 -1\nf 1 2 3 4\n"


def write(tmp_path, text, name="s.xml"):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize("text,where,what", [
    (GOOD.replace('type="ao"', 'type="magic"'), ":2:", "unknown integrator type 'magic'"),
    (GOOD.replace('<float name="radius" value="1"/>', '<float name="radius" value="1x"/>'), ":5:", "radius"),
    (GOOD.replace('<float name="radius" value="1"/>', '<float name="radiuss" value="1"/>'), ":5:", "radiuss"),
    (GOOD.replace("</scene>", "<mesh type=\"obj\"/></scene>"), ":7:", "filename"),
    (GOOD.replace("</camera>", ""), ":", "mismatched"),
    (GOOD.replace('value="{mesh}"', 'value="nowhere.obj"'), ":6:", "nowhere.obj"),
])
def test_bad_scene_gives_a_clear_error(tmp_path, capsys, text, where, what):
    (tmp_path / "quad.obj").write_text(QUAD)
    p = write(tmp_path, text.format(w=8, h=8, mesh="quad.obj"))
    assert main(["render", str(p), "-q", "-o", str(tmp_path / "o.exr")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert f"s.xml{where}" in err and what in err, err
    assert not (tmp_path / "o.exr").exists()


def test_bad_obj_names_its_line(tmp_path, capsys):
    (tmp_path / "quad.obj").write_text("v 0 0 0\nv 1 0 0\nv 1 x 0\nf 1 2 3\n")
    p = write(tmp_path, GOOD.format(w=8, h=8, mesh="quad.obj"))
    assert main(["render", str(p), "-q"]) == 2
    assert "quad.obj:3" in capsys.readouterr().err


def test_missing_scene_file(tmp_path, capsys):
    assert main(["render", str(tmp_path / "none.xml")]) == 2
    assert "none.xml" in capsys.readouterr().err


def test_devices_lists_the_default(capsys):
    assert main(["devices"]) == 0
    out = capsys.readouterr().out
    assert "*[" in out and "OpenCL C" in out


def test_ctrl_c_writes_the_partial_image(tmp_path):
    (tmp_path / "quad.obj").write_text(QUAD)
    p = write(tmp_path, GOOD.format(w=256, h=256, mesh="quad.obj"))
    out = tmp_path / "partial.exr"
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "clrender.cli", "render", str(p), "--spp", "1000000",
                             "--progress", "-o", str(out)], stderr=subprocess.PIPE, text=True, env=env)
    # Wait until rendering has started (the progress bar appears), then press Ctrl-C once.
    start = time.time()
    seen = ""
    while "rendering" not in seen and time.time() - start < 60:
        seen += proc.stderr.read(1)
    time.sleep(1.0)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    img, header = read_exr(out)
    spp = int(header["clrender.spp"])
    assert 0 < spp < 1000000 and header["clrender.interrupted"] == "True"
    assert img.max() > 0
    assert "partial" in err


def test_defines_fill_placeholders(tmp_path, capsys):
    (tmp_path / "quad.obj").write_text(QUAD)
    text = GOOD.replace('value="{w}"', 'value="$w"').replace("<scene>", '<scene><default name="w" value="4"/>')
    p = write(tmp_path, text.format(w=8, h=8, mesh="quad.obj"))
    out = tmp_path / "d.exr"
    assert main(["render", str(p), "-q", "-o", str(out), "--spp", "1", "-D", "w=6"]) == 0
    assert read_exr(out)[0].shape == (8, 6, 3)
    assert main(["render", str(p), "-q", "-o", str(out), "--spp", "1"]) == 0
    assert read_exr(out)[0].shape == (8, 4, 3)
    assert main(["render", str(p), "-q", "-D", "oops"]) == 2
    assert "name=value" in capsys.readouterr().err


def test_unknown_device_is_a_clear_error(tmp_path, capsys):
    (tmp_path / "quad.obj").write_text(QUAD)
    p = write(tmp_path, GOOD.format(w=8, h=8, mesh="quad.obj"))
    assert main(["render", str(p), "-q", "--device", "no-such-device-xyz"]) == 2
    err = capsys.readouterr().err
    assert "no-such-device-xyz" in err and "Traceback" not in err


def test_time_limit_stops_early_with_true_count(tmp_path):
    (tmp_path / "quad.obj").write_text(QUAD)
    p = write(tmp_path, GOOD.format(w=128, h=128, mesh="quad.obj"))
    out = tmp_path / "t.exr"
    start = time.time()
    main(["render", str(p), "-q", "-o", str(out), "--spp", "10000000", "--time-limit", "1.5"])
    assert time.time() - start < 30
    _, header = read_exr(out)
    assert 0 < int(header["clrender.spp"]) < 10000000


def test_unwritable_output_is_a_clear_error(tmp_path, capsys):
    (tmp_path / "quad.obj").write_text(QUAD)
    p = write(tmp_path, GOOD.format(w=8, h=8, mesh="quad.obj"))
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    assert main(["render", str(p), "-q", "--spp", "1", "-o", str(blocker / "x.exr")]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "error" in err


ASYM = """<scene>
  <integrator type="normals"/>
  <camera type="perspective"><integer name="width" value="16"/><integer name="height" value="8"/>
    <rfilter type="box"/>
    <transform name="toWorld"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/></transform></camera>
  <mesh type="sphere"><point name="center" value="0.55,0,0"/><float name="radius" value="0.3"/></mesh>
</scene>
"""


def test_nori_dialect_mirrors_the_image_and_is_recorded(tmp_path, monkeypatch):
    """A sphere at world +x, camera at +z looking at the origin: lookat's x column is cross(up, dir) = world -x,
    and upstream Nori puts camera +x on the image's left, so the sphere appears on the right (unmirrored); the
    ETH forks put it on the left. The EXR says which dialect it was rendered in; the environment variable
    selects one too."""
    p = write(tmp_path, ASYM)
    imgs = {}
    for dialect in ("upstream", "eth"):
        out = tmp_path / f"{dialect}.exr"
        assert main(["render", str(p), "-o", str(out), "--spp", "16", "-q", "--nori-dialect", dialect]) == 0
        img, meta = read_exr(out)
        assert meta["clrender.nori_dialect"] == dialect
        imgs[dialect] = img.sum(axis=(0, 2))
    up, eth = imgs["upstream"], imgs["eth"]
    assert up[8:].sum() > 0 and up[:8].sum() == 0      # sphere on the right half
    # mirror images of each other (the pixel jitter differs, so the coverage of edge pixels differs slightly)
    np.testing.assert_array_equal(eth > 0, up[::-1] > 0)
    np.testing.assert_allclose(eth.sum(), up.sum(), rtol=0.15)
    monkeypatch.setenv("CLRENDER_NORI_DIALECT", "eth")
    out = tmp_path / "env.exr"
    assert main(["render", str(p), "-o", str(out), "--spp", "16", "-q"]) == 0
    img, meta = read_exr(out)
    assert meta["clrender.nori_dialect"] == "eth"
    np.testing.assert_array_equal(img.sum(axis=(0, 2)), eth)


def test_bad_dialect_in_the_environment_is_a_clear_error(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("CLRENDER_NORI_DIALECT", "mitsuba")
    assert main(["render", str(write(tmp_path, ASYM)), "-o", str(tmp_path / "x.exr"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "CLRENDER_NORI_DIALECT" in err and "upstream" in err and "Traceback" not in err


def test_sample_range_beyond_32_bits_is_an_option_error(tmp_path, capsys):
    # It used to reach the renderer and leave as a ValueError traceback.
    (tmp_path / "quad.obj").write_text(QUAD)
    p = write(tmp_path, GOOD.format(w=8, h=8, mesh="quad.obj"))
    assert main(["render", str(p), "-q", "--sample-range", "4294967295:4", "-o", str(tmp_path / "o.exr")]) == 2
    err = capsys.readouterr().err
    assert "--sample-range" in err and "2^32" in err, err
    assert not list(tmp_path.glob("*.exr"))


def _quad_scene(tmp_path, w=8, h=8):
    (tmp_path / "quad.obj").write_text(QUAD)
    return write(tmp_path, GOOD.format(w=w, h=h, mesh="quad.obj"))


def _film(h=5, w=7, seed=3):
    from clrender.film import Film

    rng = np.random.default_rng(seed)
    img = rng.random((h, w, 3)) * np.array([1.0, 8.0, 60.0])     # beyond 1: the float formats keep it
    img[0, 0] = [-0.25, 0.0, 1e-3]                                # a Mitchell filter's negative lobe
    ones = np.ones((h, w))
    return Film(w, h, img, ones, img * img, ones, np.zeros((h, w), np.int64), {"spp": 1})


def test_film_writes_the_format_its_extension_names(tmp_path):
    """PFM keeps the float32 image exactly; Radiance HDR to its 8-bit shared-exponent precision (negative values
    become 0); PNG and JPEG are 8-bit sRGB (JPEG within its loss). Read back by Pillow, our readers and, for HDR
    and PFM, Mitsuba 3.9.1 when installed."""
    from PIL import Image

    from clrender.film import to_srgb8
    from clrender.textures.imagefile import read_image

    film = _film()
    img = film.image
    written = {ext: film.write(tmp_path / f"o{ext}") for ext in (".pfm", ".hdr", ".png", ".jpg", ".JPEG", ".exr")}
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in written.values())
    np.testing.assert_array_equal(read_image(written[".pfm"]), img)
    pos = np.maximum(img, 0)
    hdr = read_image(written[".hdr"])
    assert np.all(np.abs(hdr - pos) <= pos.max(axis=-1, keepdims=True) / 128 + 1e-7)
    assert hdr[0, 0, 0] == 0
    with Image.open(written[".png"]) as im:
        assert im.format == "PNG"
        np.testing.assert_array_equal(np.asarray(im), to_srgb8(img))
    for ext in (".jpg", ".JPEG"):
        with Image.open(written[ext]) as im:
            assert im.format == "JPEG"
            assert np.abs(np.asarray(im, np.float64) - to_srgb8(img)).mean() < 8
    np.testing.assert_array_equal(read_exr(written[".exr"])[0], img)
    try:
        import mitsuba as mi

        mi.set_variant("scalar_rgb")
    except (ImportError, AttributeError):
        return    # tests/mitsuba/ is found as a namespace package without Mitsuba
    np.testing.assert_array_equal(np.array(mi.Bitmap(str(written[".pfm"]))), img)
    np.testing.assert_array_equal(np.array(mi.Bitmap(str(written[".hdr"]))), hdr)


@pytest.mark.parametrize("name", ["o.png", "o.jpg", "o.hdr", "o.pfm", "o.PNG"])
def test_output_names_its_format(tmp_path, capsys, name):
    """-o NAME.png/.jpg/.hdr/.pfm writes that file alone (no EXR, no preview), the same image as the EXR."""
    from clrender.textures.imagefile import read_image

    p = _quad_scene(tmp_path, w=12)
    (tmp_path / "out").mkdir()
    assert main(["render", str(p), "-q", "--spp", "2", "-o", str(tmp_path / "out" / name)]) == 0
    assert [f.name for f in (tmp_path / "out").iterdir()] == [name]
    magic = {"png": b"\x89PNG", "jpg": b"\xff\xd8", "hdr": b"#?RA", "pfm": b"PF\n"}[name.lower()[2:]]
    assert (tmp_path / "out" / name).read_bytes().startswith(magic)
    assert f"wrote {tmp_path / 'out' / name}:" in capsys.readouterr().err
    assert main(["render", str(p), "-q", "--spp", "2", "-o", str(tmp_path / "ref.exr")]) == 0
    ref = read_exr(tmp_path / "ref.exr")[0]
    back = read_image(tmp_path / "out" / name)
    if name.endswith(".pfm"):
        np.testing.assert_array_equal(back, ref)
    elif name.endswith(".hdr"):
        assert np.all(np.abs(back - ref) <= ref.max(axis=-1, keepdims=True) / 128 + 1e-7)
    elif name.lower().endswith(".png"):
        from clrender.film import to_srgb8
        from clrender.textures.imagefile import srgb_to_linear

        np.testing.assert_allclose(back, srgb_to_linear(to_srgb8(ref) / 255.0), atol=1e-6)
    else:
        assert np.abs(back - ref).mean() < 0.03


def test_output_extension_errors(tmp_path, capsys):
    p = _quad_scene(tmp_path)
    assert main(["render", str(p), "-q", "--spp", "1", "-o", str(tmp_path / "o.bmp")]) == 2
    err = capsys.readouterr().err
    assert "must end in .exr, .png, .jpg, .jpeg, .hdr, .pfm" in err and "'.bmp'" in err, err
    assert main(["render", str(p), "-q", "--sample-range", "0:1", "-o", str(tmp_path / "o.png")]) == 2
    assert "accumulator EXR" in capsys.readouterr().err
    assert list(tmp_path.glob("o.*")) == []
