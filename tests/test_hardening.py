"""Smaller promises of the hardened command line: progress bar only on a terminal (or --progress), output
files with the umask's permissions, scene columns in linear time, the film checked against memory, and
`cpu`/`gpu` never choosing a simulator."""
import os
import time
from types import SimpleNamespace

import numpy as np
import pytest

from clrender.cli import main
from clrender.errors import SceneError

SCENE = """<scene>
  <integrator type="normals"/>
  <camera type="perspective"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>
    <transform name="toWorld"><lookat origin="0,0,3" target="0,0,0" up="0,1,0"/></transform></camera>
  <mesh type="sphere"><float name="radius" value="1"/></mesh>
</scene>
"""


def _scene(tmp_path, w=8, h=8):
    p = tmp_path / "s.xml"
    p.write_text(SCENE.format(w=w, h=h))
    return p


def test_no_progress_bar_unless_a_terminal_or_asked(tmp_path, capsys):
    p = _scene(tmp_path)
    assert main(["render", str(p), "--spp", "2", "-o", str(tmp_path / "a.exr")]) == 0
    assert "spp/s" not in capsys.readouterr().err  # stderr is not a terminal here
    assert main(["render", str(p), "--spp", "2", "--progress", "-o", str(tmp_path / "b.exr")]) == 0
    assert "rendering" in capsys.readouterr().err


@pytest.mark.parametrize("umask,mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_images_get_the_umask_permissions(tmp_path, umask, mode):
    p = _scene(tmp_path)
    old = os.umask(umask)
    try:
        assert main(["render", str(p), "-q", "--spp", "1", "-o", str(tmp_path / "o.exr")]) == 0
    finally:
        os.umask(old)
    for name in ("o.exr", "o.png"):
        assert (tmp_path / name).stat().st_mode & 0o777 == mode, name


def test_one_long_line_parses_in_linear_time():
    # Columns used to be found by decoding the line's prefix per element: quadratic on one long line.
    from clrender.scene.xmlparser import parse_string

    spheres = "".join(f'<mesh type="sphere"><point name="center" value="{i},0,0"/>'
                      f'<float name="radius" value="0.35"/></mesh>' for i in range(5000))
    texts = {sep: f"<scene>{sep}" + spheres.replace("</mesh>", "</mesh>" + sep) + "</scene>" for sep in ("\n", " ")}
    times = {}
    for sep, text in texts.items():
        for _ in range(2):
            t0 = time.perf_counter()
            parse_string("<!-- \u00e9 -->" + text)  # a non-ASCII character: the per-line table is built
            times[sep] = min(times.get(sep, 1e9), time.perf_counter() - t0)
    assert times[" "] < 3 * times["\n"] + 0.2, times


def test_columns_count_characters_on_long_lines():
    from clrender.scene.xmlparser import parse_string

    text = "<scene>" + "<!-- \u00e9\u00e9 -->" * 1000 + "<bogus/></scene>"
    with pytest.raises(SceneError) as e:
        parse_string(text)
    assert e.value.location.col == len("<scene>" + "<!-- \u00e9\u00e9 -->" * 1000) + 1


def test_film_is_checked_against_device_and_host_memory(monkeypatch):
    from clrender import memcheck
    from clrender.memcheck import check_film_fits

    import pyopencl as cl

    class Props(dict):
        def location(self, name):
            return f"s.xml:4 ({name})"

    spec = SimpleNamespace(props=Props(width=1, height=1), location="s.xml:3")
    scene = SimpleNamespace(width=20000, height=10000, camera=SimpleNamespace(spec=spec))
    gpu = SimpleNamespace(max_mem_alloc_size=2**30, global_mem_size=4 * 2**30, type=cl.device_type.GPU)
    with pytest.raises(SceneError) as e:
        check_film_fits(scene, gpu)
    assert "20000 x 10000" in str(e.value) and "per buffer" in str(e.value) and "(width)" in str(e.value)
    gpu.max_mem_alloc_size = 2**40
    with pytest.raises(SceneError, match="device memory"):
        check_film_fits(scene, gpu)
    gpu.global_mem_size = 2**40
    monkeypatch.setattr(memcheck, "available_host_memory", lambda: 2**45)
    check_film_fits(scene, gpu)
    monkeypatch.setattr(memcheck, "available_host_memory", lambda: 2**33)
    with pytest.raises(SceneError, match="host memory"):
        check_film_fits(scene, gpu)


def test_cpu_and_gpu_mean_one_kind_of_device(monkeypatch):
    import pyopencl as cl

    from clrender.device import context

    t = cl.device_type
    sim = SimpleNamespace(type=t.CPU | t.GPU | t.ACCELERATOR | t.DEFAULT, name="Oclgrind Simulator", int_ptr=1)
    cpu = SimpleNamespace(type=t.CPU, name="pthread CPU", int_ptr=2)
    plat = SimpleNamespace(name="P")
    monkeypatch.setattr(context, "list_devices", lambda: [(plat, sim), (plat, cpu)])
    assert context.choose_device("cpu")[1] is cpu
    with pytest.raises(context.DeviceError, match="no GPU"):
        context.choose_device("gpu")
    assert context.choose_device("oclgrind")[1] is sim


def test_the_default_device_is_never_a_simulator(monkeypatch):
    """When no CPU device builds kernels (a PoCL that cannot write its cache, say), the default used to be the first
    device listed: the Oclgrind simulator, chosen without a word. Now a real GPU, else an error naming why."""
    import pyopencl as cl

    from clrender.device import context

    t = cl.device_type
    sim = SimpleNamespace(type=t.CPU | t.GPU | t.ACCELERATOR | t.DEFAULT, name="Oclgrind Simulator", int_ptr=1)
    cpu = SimpleNamespace(type=t.CPU, name="pthread CPU", int_ptr=2)
    gpu = SimpleNamespace(type=t.GPU, name="Some GPU", int_ptr=3)
    oclgrind = SimpleNamespace(name="Oclgrind", version="OpenCL 1.2")
    pocl = SimpleNamespace(name="Portable Computing Language", version="OpenCL 3.0 PoCL 3.0")
    monkeypatch.setattr(context, "build_check", lambda p, d: "cannot write its kernel cache" if d is cpu else None)
    monkeypatch.setattr(context, "list_devices", lambda: [(oclgrind, sim), (pocl, cpu)])
    with pytest.raises(context.DeviceError, match="cannot write its kernel cache") as e:
        context.choose_device(None)
    assert "--device" in str(e.value)
    monkeypatch.setattr(context, "list_devices", lambda: [(oclgrind, sim), (pocl, cpu), (oclgrind, gpu)])
    assert context.choose_device(None)[1] is gpu


def test_a_successful_build_says_nothing_unless_asked(ctx, monkeypatch, capfd):
    """A build log of a successful build (NVIDIA's driver writes one for our kernels) is not shown on every
    render as pyopencl's CompilerWarning or the compiler's stderr; PYOPENCL_COMPILER_OUTPUT=1 shows both."""
    import warnings

    import pyopencl as cl

    from clrender.device.program import build_program

    def build(tag):
        src = f'#warning "clrender test warning {tag}"\n__kernel void k(__global int* a) {{ a[0] = 1; }}'
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            build_program(ctx, src, with_types=False, use_cache=False)
        return [w for w in seen if issubclass(w.category, cl.CompilerWarning)], capfd.readouterr().err

    monkeypatch.delenv("PYOPENCL_COMPILER_OUTPUT", raising=False)
    quiet, err = build("quiet")
    assert quiet == [] and "warning" not in err
    monkeypatch.setenv("PYOPENCL_COMPILER_OUTPUT", "1")
    loud, err = build("loud")
    assert loud or "clrender test warning loud" in err


def test_overflowing_pixel_sums_never_reach_the_image(tmp_path, capsys):
    """Finite samples of absurd size (an albedo of 3e38) overflow a pixel's float32 sums on the device; those
    pixels used to be written as inf. Their samples are dropped and counted like NaN/Inf ones."""
    from clrender.film import read_exr

    p = tmp_path / "s.xml"
    p.write_text(SCENE.format(w=16, h=16).replace('type="normals"', 'type="path_mis"').replace(
        '<float name="radius" value="1"/>', '<float name="radius" value="1"/><bsdf type="diffuse"><color '
        'name="albedo" value="3e38"/></bsdf>').replace(
        "</scene>", '<emitter type="point"><point name="position" value="0,2,3"/><color name="power" value="50"/>'
                    '</emitter></scene>'))
    assert main(["render", str(p), "-q", "--spp", "8", "-o", str(tmp_path / "o.exr")]) == 0
    img, header = read_exr(tmp_path / "o.exr")
    assert np.isfinite(img).all()
    assert int(header["clrender.dropped_samples"]) > 0
    assert img.max() > 1e30  # the pixels that did not overflow keep their (huge) values
    assert "NaN/Inf samples dropped" in capsys.readouterr().err


def test_film_drops_the_samples_of_overflowed_pixels():
    from clrender.film import Film

    ones = np.ones((1, 2))
    film = Film(2, 1, np.array([[[1.0, 2, 3], [np.inf, 0, 0]]]), ones.copy(), ones.copy()[..., None] * [1, 1, 1],
                np.array([[4.0, 5.0]]), np.zeros((1, 2), np.int64), {"dropped_samples": 0})
    assert np.isfinite(film.image).all() and film.image[0, 1].tolist() == [0, 0, 0]
    assert film.dropped.tolist() == [[0, 5]] and film.metadata["dropped_samples"] == 5
    assert film.image[0, 0].tolist() == [1, 2, 3]


def test_renders_with_an_unwritable_home_and_names_an_unwritable_pocl_cache(tmp_path):
    """A container run as another user often has a home it cannot write: PoCL then failed to load (no cache) and
    pyopencl failed on its first launch (its own caches). Now the caches go to the temporary folder; a
    POCL_CACHE_DIR the user set that cannot be written is named in the error."""
    import subprocess
    import sys
    from pathlib import Path

    p = _scene(tmp_path)
    root = Path(__file__).resolve().parents[1]
    env = {k: v for k, v in os.environ.items() if k not in ("POCL_CACHE_DIR", "XDG_CACHE_HOME")}
    env.update(HOME="/proc/clrender-no-home", PYTHONPATH=str(root))
    run = [sys.executable, "-m", "clrender.cli", "render", str(p), "-q", "--spp", "1"]
    proc = subprocess.run(run + ["-o", str(tmp_path / "a.exr")], env=env, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "Portable Computing Language" in proc.stderr and "Traceback" not in proc.stderr
    env["POCL_CACHE_DIR"] = "/proc/clrender-no-cache"
    proc = subprocess.run(run + ["-o", str(tmp_path / "b.exr")], env=env, capture_output=True, text=True,
                          timeout=600)
    assert "POCL_CACHE_DIR" in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    from clrender.device import context, intel_cpu

    context._cl()
    if not intel_cpu.state["installed"]:
        assert proc.returncode == 2, proc.stderr
        return
    # With the intel-cpu extra, its runtime renders instead, with a warning that says why PoCL did not load; and
    # on that runtime, which pyopencl caches binaries for (PoCL caches its own), with the home unwritable
    assert proc.returncode == 0 and "PoCL did not load; rendering on Intel" in proc.stderr, proc.stderr
    del env["POCL_CACHE_DIR"]
    proc = subprocess.run(run + ["-o", str(tmp_path / "c.exr"), "--device", "intel"], env=env, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0 and "Traceback" not in proc.stderr, proc.stderr


def test_pyopencl_caches_off_with_a_warning_where_nothing_can_be_written(monkeypatch, caplog, tmp_path):
    """Where neither $XDG_CACHE_HOME nor the temporary folder can be written, pyopencl's fallback was a traceback
    (Intel's CPU runtime, whose binaries pyopencl caches): its caches are turned off instead, with a warning; where
    the temporary folder can be written they go there, silently."""
    from clrender.device import context

    caches = context._pyopencl_caches.__wrapped__   # the function, not its once-per-process cache
    monkeypatch.delenv("PYOPENCL_NO_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", "/proc/clrender-no-xdg")
    monkeypatch.setattr(context, "_temp_cache_root", lambda: "/proc/clrender-no-tmp")
    with caplog.at_level("WARNING", logger="clrender"):
        caches()
    assert os.environ.get("PYOPENCL_NO_CACHE") == "1"
    assert "/proc/clrender-no-xdg" in caplog.text and "pyopencl's caches are off" in caplog.text
    monkeypatch.delenv("PYOPENCL_NO_CACHE")
    caplog.clear()
    tmp = str(tmp_path)
    monkeypatch.setattr(context, "_temp_cache_root", lambda: tmp)
    with caplog.at_level("WARNING", logger="clrender"):
        caches()
    assert os.environ["XDG_CACHE_HOME"] == tmp and "PYOPENCL_NO_CACHE" not in os.environ and not caplog.text


def test_a_vanishing_sun_packs_without_numpy_warnings(tmp_path):
    # A distantdisk of thetaA 1e-30 printed numpy's "overflow encountered in cast" (its pdf is inf in float32).
    import warnings

    from clrender.loader import load_scene
    from clrender.pack import pack_scene

    p = tmp_path / "s.xml"
    p.write_text(SCENE.format(w=4, h=4).replace("</scene>", '<emitter type="distantdisk"><color name="radiance" '
                                                            'value="1"/><float name="thetaA" value="1e-30"/>'
                                                            '</emitter></scene>'))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        pack_scene(load_scene(p))
