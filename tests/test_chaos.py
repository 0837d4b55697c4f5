"""Chaos: `clrender render` killed with SIGKILL at random moments (during the load, the kernel build, the
passes and the write). Whatever the moment, the -o path holds either nothing, the previous image, or a
complete new one -- never a partial or corrupt file (images are written to a temporary file and renamed)."""
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from bigmesh import write_grid_ply
from clrender.film import read_exr

ROOT = Path(__file__).resolve().parents[1]
W, H = 320, 240
SCENE = f"""<scene>
  <integrator type="ao"/>
  <camera type="perspective"><integer name="width" value="{W}"/><integer name="height" value="{H}"/>
    <transform name="toWorld"><lookat origin="0,1.5,4" target="0,0.5,0" up="0,1,0"/></transform></camera>
  <mesh type="ply"><string name="filename" value="grid.ply"/></mesh>
</scene>
"""


def _start(tmp_path, out, spp):
    scene = tmp_path / "s.xml"
    if not scene.exists():
        write_grid_ply(tmp_path / "grid.ply")  # 100k triangles: the load and BVH build take a while
        scene.write_text(SCENE)
    return subprocess.Popen([sys.executable, "-m", "clrender.cli", "render", str(scene), "-q", "--spp", str(spp),
                             "-o", str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env=dict(os.environ, PYTHONPATH=str(ROOT)))


def _check_outputs(out: Path, previous):
    """Nothing, the previous image, or a complete image -- for both the EXR and its PNG."""
    if out.exists():
        img, header = read_exr(out)  # a partial file does not read
        assert img.shape == (H, W, 3)
        assert int(header["clrender.spp"]) >= 1
        assert np.isfinite(img).all()
        if previous is not None and int(header["clrender.spp"]) == previous[1]:
            assert np.array_equal(img, previous[0])
    png = out.with_suffix(".png")
    if png.exists():
        from PIL import Image

        with Image.open(png) as im:
            im.load()  # raises on a truncated file
            assert im.size == (W, H)


def _temporaries(out: Path) -> set:
    return {p.name for p in out.parent.iterdir() if p.name.startswith(f".{out.name}.")}


def _kill_at(tmp_path, out, delay=None, spp=4, when_writing=None, previous=None):
    old = _temporaries(out)  # earlier kills leave hidden temporaries behind; wait for a new one
    proc = _start(tmp_path, out, spp)
    try:
        if when_writing is not None:
            # Kill `when_writing` seconds after a temporary image file appears next to the output: during
            # the EXR write, its rename, or the PNG's.
            deadline = time.time() + 120
            while time.time() < deadline and proc.poll() is None:
                if _temporaries(out) - old:
                    break
                time.sleep(0.001)
            time.sleep(when_writing)
        else:
            time.sleep(delay)
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait(timeout=60)
    _check_outputs(out, previous)


def test_kill_9_never_leaves_a_partial_image(tmp_path):
    out = tmp_path / "o.exr"
    # A complete render first: its image is the "previous" one every later kill must leave intact or replace.
    start = time.time()
    proc = _start(tmp_path, out, 2)
    assert proc.wait(timeout=300) == 0
    total = time.time() - start
    previous = (read_exr(out)[0], 2)
    rng = random.Random(12)
    # Load, build, passes: spread over the whole run; then twice exactly during the write.
    for frac in (0.15, 0.5, 0.85):
        _kill_at(tmp_path, out, delay=total * (frac + rng.uniform(-0.05, 0.05)), spp=2, previous=previous)
    for after in (0.02,):
        _kill_at(tmp_path, out, spp=2, when_writing=after, previous=previous)
    assert not (tmp_path / "o.exr").is_dir()


@pytest.mark.slow
def test_kill_9_many_times(tmp_path):
    out = tmp_path / "o.exr"
    rng = random.Random(7)
    for i in range(30):
        if i % 3 == 2:
            _kill_at(tmp_path, out, spp=1, when_writing=rng.uniform(0.0, 0.2))
        else:
            _kill_at(tmp_path, out, delay=rng.uniform(0.0, 6.0), spp=rng.choice([1, 4]))
