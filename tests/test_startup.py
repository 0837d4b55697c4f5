"""What makes `clrender render` start and finish sooner keeps its behaviour: the PNG preview's own encoder, the
layout cache that follows plugin registrations, and the command's fast exit and BLAS thread setting."""
import io
import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from clrender.bsdfs.bsdf import Bsdf
from clrender.device import codegen, layout
from clrender.film import read_exr, to_srgb8
from clrender.png import encode_png
from clrender.scene import registry

SCENE = """<scene>
  <integrator type="path_mis"/>
  <camera type="perspective"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>
    <transform name="toWorld"><lookat origin="0,1.5,4" target="0,0.5,0" up="0,1,0"/></transform></camera>
  <mesh type="obj"><string name="filename" value="quad.obj"/>
    <emitter type="area"><color name="radiance" value="1"/></emitter></mesh>
  <mesh type="sphere"><point name="center" value="0,0.5,0"/><float name="radius" value="0.5"/></mesh>
</scene>
"""
QUAD = "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 4 3 2\n"  # facing +y, the camera


def write_scene(d, w=24, h=16):
    (d / "quad.obj").write_text(QUAD)
    p = d / "s.xml"
    p.write_text(SCENE.format(w=w, h=h))
    return p


def decode(data: bytes) -> np.ndarray:
    im = Image.open(io.BytesIO(data))
    assert im.mode == "RGB" and im.format == "PNG"
    return np.asarray(im)


@pytest.mark.parametrize("shape", [(1, 1), (1, 7), (9, 1), (37, 53), (256, 256)])
def test_png_decodes_to_the_same_pixels(shape):
    rng = np.random.default_rng(sum(shape))
    h, w = shape
    noise = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    ramp = np.clip(np.add.outer(np.arange(h), np.arange(w))[..., None] * [3, 5, 7], 0, 255).astype(np.uint8)
    for img in (noise, ramp, np.zeros((h, w, 3), np.uint8), np.full((h, w, 3), 255, np.uint8)):
        assert np.array_equal(decode(encode_png(img)), img)


def test_png_filters_smooth_images_well():
    # The Average filter turns a smooth ramp into near-constant bytes: far smaller than the raw pixels.
    h, w = 128, 128
    ramp = (np.add.outer(np.arange(h), np.arange(w))[..., None] * [1, 0.5, 0.25] / 2).astype(np.uint8)
    assert len(encode_png(ramp)) < h * w * 3 / 20


@pytest.mark.parametrize("bad", [np.zeros((4, 4), np.uint8), np.zeros((4, 4, 3), np.float32),
                                 np.zeros((4, 4, 4), np.uint8), np.zeros((0, 4, 3), np.uint8)])
def test_png_refuses_what_is_not_an_rgb8_image(bad):
    with pytest.raises(ValueError, match="uint8 image"):
        encode_png(bad)


class Throwaway(Bsdf):
    """<bsdf type="startup_throwaway"/> (test only: registered, looked at, unregistered)"""
    kernel = "tests/kernels/tinted.h"
    prefix = "startup_throwaway"
    PARAMS = [("albedo", "float4")]
    FLAGS = ("DIFFUSE",)


def test_row_layouts_follow_registrations():
    assert "startup_throwaway" not in layout.dtype("Bsdf").names
    registry.register("bsdf", "startup_throwaway")(Throwaway)
    try:
        assert "startup_throwaway" in layout.dtype("Bsdf").names
        assert " startup_throwaway;" in codegen.c_header()
    finally:
        registry.unregister("bsdf", "startup_throwaway")
    assert "startup_throwaway" not in layout.dtype("Bsdf").names
    assert " startup_throwaway;" not in codegen.c_header()


def test_the_command_limits_blas_threads_unless_the_user_chose(monkeypatch):
    from clrender.cli import main

    monkeypatch.setattr(sys, "argv", ["clrender", "--version"])
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    with pytest.raises(SystemExit):
        main()
    assert os.environ["OPENBLAS_NUM_THREADS"] == "1"
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "3")
    with pytest.raises(SystemExit):
        main()
    assert os.environ["OPENBLAS_NUM_THREADS"] == "3"


def test_the_command_writes_everything_before_its_fast_exit(tmp_path):
    p = write_scene(tmp_path, w=64, h=48)
    out = tmp_path / "img.exr"
    proc = subprocess.run([sys.executable, "-m", "clrender.cli", "render", str(p), "--spp", "4", "-o", str(out)],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "wrote" in proc.stderr and "Traceback" not in proc.stderr
    img, header = read_exr(out)
    assert header["clrender.spp"] == "4" and img.shape == (48, 64, 3) and img.max() > 0
    png = np.asarray(Image.open(out.with_suffix(".png")))
    assert np.array_equal(png, to_srgb8(img))
    assert sorted(f.name for f in tmp_path.iterdir()) == ["img.exr", "img.png", "quad.obj", "s.xml"]
