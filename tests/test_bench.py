"""`clrender bench`: ray counting in the kernels, the measurement's JSON, --compare, --plot, device listing."""
import json
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

from analytic_scenes import camera, plane_mesh
from clrender import bench
from clrender.cli import main
from clrender.errors import ClrenderError
from clrender.renderer import Renderer

ROOT = Path(__file__).resolve().parents[1]
CORNELL = ROOT / "scenes" / "cornell" / "cornell_path_mis.xml"


def _scene(tmp_path, integrator, w=4, h=3, target=(0.2, -0.1, 0.0), origin=(2.5, 0.1, 1.5)):
    xml = (f'<scene><integrator type="{integrator}"/>{camera(w, h, target=np.array(target), origin=origin)}'
           f'{plane_mesh(tmp_path / "plane.obj")}</scene>')
    p = tmp_path / f"{integrator}.xml"
    p.write_text(xml)
    return bench.load_bench_scene(p)[0]


def _rays(scene, spp=3, seed=1):
    film = Renderer(scene, count_rays=True).render(spp=spp, seed=seed)
    assert film.metadata["rays_total"] == sum(film.stats.rays)
    return film.stats.rays


def test_normals_traces_exactly_one_camera_ray_per_sample(tmp_path):
    scene = _scene(tmp_path, "normals")
    assert _rays(scene) == (4 * 3 * 3, 0, 0)


def test_ao_traces_one_shadow_ray_per_hit(tmp_path):
    scene = _scene(tmp_path, "ao")  # every camera ray hits the plane
    assert _rays(scene) == (36, 0, 36)
    # looking away from the plane (up +z): every camera ray escapes, no shadow rays
    away = _scene(tmp_path, "ao", target=(5.0, 0.1, 3.0), origin=(2.5, 0.1, 1.5))
    assert _rays(away) == (36, 0, 0)


def test_counting_does_not_change_the_image():
    scene = bench.load_bench_scene(CORNELL, width=24, height=20)[0]
    # spp=2 is two passes of one sample whatever the timing, so both renders sum in the same order
    # rays are counted by the filter-sampling film's kernels (a splatting film's default would be another image)
    a = Renderer(scene, reconstruction="sampling").render(spp=2, seed=7)
    b = Renderer(scene, count_rays=True).render(spp=2, seed=7)
    assert np.array_equal(a.image, b.image)
    assert a.stats.rays is None and b.stats.rays[0] == 24 * 20 * 2
    assert b.stats.rays[1] > 0 and b.stats.rays[2] > 0


@pytest.fixture(scope="module")
def bench_run(tmp_path_factory):
    """One short CLI run on the Cornell box at 24x20 with a reference, --json and (if possible) --plot."""
    d = tmp_path_factory.mktemp("bench")
    scene = bench.load_bench_scene(CORNELL, width=24, height=20)[0]
    ref = d / "ref.exr"
    Renderer(scene).render(spp=64, seed=99).write_exr(ref)
    out = d / "a.json"
    argv = ["bench", str(CORNELL), "--width", "24", "--height", "20", "--spp", "4", "--repeat", "2",
            "--json", str(out), "--reference", str(ref), "-q"]
    png = None
    try:
        import matplotlib  # noqa: F401

        png = d / "a.png"
        argv += ["--plot", str(png)]
    except ImportError:
        pass
    return d, argv, out, png


def test_bench_writes_json_with_all_figures(bench_run, capsys):
    d, argv, out, png = bench_run
    assert main(argv) == 0
    table = capsys.readouterr().out
    assert "cornell_path_mis" in table and "samples/s" in table and "rays/s" in table
    res = json.loads(out.read_text())
    for k in ("schema", "clrender_version", "git_revision", "timestamp", "host", "settings", "devices",
              "results"):
        assert k in res
    dev = res["devices"][0]
    for k in ("name", "platform", "driver_version", "opencl_version", "opencl_c_version"):
        assert dev[k]
    (row,) = res["results"]
    assert row["status"] == "ok" and row["integrator"] == "path_mis"
    assert (row["width"], row["height"], row["spp"]) == (24, 20, 4)
    assert len(row["scene_hash"]) == 32  # the package's one content hash (scenesource.SceneSource)
    assert row["scene_hash"] == bench.scene_hash(CORNELL)
    sps, rps = row["samples_per_second"], row["rays_per_second"]
    assert len(sps["values"]) == 2 and sps["min"] <= sps["median"] <= sps["max"]
    assert sps["median"] > 0
    assert rps["median"] >= sps["median"]  # path_mis: at least the camera ray per sample
    rays = row["rays"]
    assert rays["camera"] == 24 * 20 * 4 and rays["total"] == rays["camera"] + rays["closest"] + rays["shadow"]
    b = row["build"]
    assert b["cold_total"] > 0 and b["warm_total"] > 0 and b["cold_program"] > 0
    for k in ("load_seconds", "pack_seconds", "bvh_build_seconds", "device_memory_bytes", "host_peak_rss_bytes"):
        assert row[k] > 0
    assert row["pass_seconds"]["median"] > 0
    curve = row["convergence"]
    assert [c["spp"] for c in curve] == [1, 2, 4]
    assert curve[-1]["relmse"] < curve[0]["relmse"]
    assert all(b["seconds"] > a["seconds"] for a, b in zip(curve, curve[1:]))
    if png is not None:
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_compare_prints_ratios(bench_run, capsys, tmp_path):
    d, argv, out, png = bench_run
    if not out.exists():
        assert main(argv) == 0
    res = json.loads(out.read_text())
    row = res["results"][0]
    for k in ("samples_per_second", "rays_per_second"):
        row[k]["median"] *= 2
    row["pass_seconds"]["median"] /= 2
    b = tmp_path / "b.json"
    b.write_text(json.dumps(res))
    capsys.readouterr()
    assert main(["bench", "--compare", str(out), str(b)]) == 0
    text = capsys.readouterr().out
    assert "cornell_path_mis" in text
    line = next(ln for ln in text.splitlines() if ln.startswith("cornell_path_mis"))
    assert line.count("2.000x") == 2 and "0.500x" in line and "1.000x" in line


def test_compare_notes_what_differs():
    def result(scene_hash, spp=4):
        row = {"status": "ok", "scene": "s", "integrator": "path_mis", "device": "d", "scene_hash": scene_hash,
               "width": 8, "height": 8, "spp": spp, "samples_per_second": {"median": 1.0}}
        return {"results": [row]}

    new, other = "0" * 32, "1" * 32
    assert bench.compare(result(new), result(new))[0]["note"] == ""
    assert bench.compare(result(new), result(other))[0]["note"] == "scene files differ"
    # a result from before the one content hash (sha256, 64 digits) says nothing about the files
    old = bench.compare(result("2" * 64), result(new, spp=8))[0]["note"]
    assert old == "scene hashes of different clrender versions; resolution/spp differ"


def test_compare_rejects_other_json(tmp_path, capsys):
    a = tmp_path / "x.json"
    a.write_text("{}")
    assert main(["bench", "--compare", str(a), str(a)]) == 2
    assert "not a clrender bench result" in capsys.readouterr().err


def test_skipped_device_is_reported_not_a_crash(monkeypatch):
    real = bench.resolve_devices

    def fake(devices=None):
        devs = real(None)
        broken = dict(devs[0], index=99, spec="99", name="broken device", ok=False,
                      reason="error: unknown target CPU 'generic'")
        return devs + [broken]

    monkeypatch.setattr(bench.measure, "resolve_devices", fake)
    res = bench.run_benchmark([CORNELL], devices="all", integrator="normals", width=16, height=8, spp=1,
                              repeat=1, cold=False)
    status = {r["device"]: r["status"] for r in res["results"]}
    assert status["broken device"] == "skipped" and list(status.values()).count("ok") == 1
    table = bench.format_table(res)
    assert "skipped" in table and "unknown target CPU" in table
    ok = next(r for r in res["results"] if r["status"] == "ok")
    assert ok["integrator"] == "normals" and ok["rays"]["per_sample"] == 1.0


def test_the_wavefront_is_benchmarked_and_its_rays_counted_by_the_megakernel():
    """`bench --driver wavefront` times the wavefront; the rays per sample it reports are the megakernel's count of
    the same samples (the same rays), and equal to a megakernel row's."""
    res = {d: bench.run_benchmark([CORNELL], width=16, height=8, spp=2, repeat=1, cold=False, driver=d)["results"][0]
           for d in ("wavefront", "megakernel")}
    assert res["wavefront"]["status"] == "ok" and res["wavefront"]["driver"] == "wavefront"
    assert res["megakernel"]["driver"] == "megakernel"
    assert res["wavefront"]["rays"] == res["megakernel"]["rays"]
    assert res["wavefront"]["samples_per_second"]["median"] > 0


def test_devices_all_skips_a_simulator_unless_named(monkeypatch):
    # `--devices all` used to run the default set on the Oclgrind simulator too (installed by the test extra):
    # hours of a simulated CPU. It is listed as skipped; named, it is benchmarked.
    from types import SimpleNamespace

    import pyopencl as cl

    from clrender.device import context

    t = cl.device_type
    sim = SimpleNamespace(type=t.CPU | t.GPU | t.ACCELERATOR, name="Oclgrind Simulator", int_ptr=1, version="1.2",
                          vendor="v", opencl_c_version="1.2", driver_version="21", max_compute_units=1,
                          global_mem_size=2**27)
    cpu = SimpleNamespace(**{**vars(sim), "type": t.CPU, "name": "pthread CPU", "int_ptr": 2})
    plat = SimpleNamespace(name="P", version="OpenCL 3.0")
    monkeypatch.setattr(context, "list_devices", lambda: [(plat, sim), (plat, cpu)])
    monkeypatch.setattr(context, "build_check", lambda p, d: None)
    every = {d["name"]: d for d in bench.resolve_devices("all")}
    assert not every["Oclgrind Simulator"]["ok"] and "simulator" in every["Oclgrind Simulator"]["reason"]
    assert every["pthread CPU"]["ok"]
    assert bench.resolve_devices("oclgrind")[0]["ok"]


def test_plot_without_matplotlib_names_the_extra(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(ClrenderError, match=r'pip install "clrender\[plot\]"'):
        bench.plot({"results": []}, tmp_path / "x.png")


def test_default_set_needs_the_scenes_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(bench.discovery, "__file__", str(tmp_path / "pkg" / "clrender" / "bench" / "discovery.py"))
    with pytest.raises(ClrenderError, match="--scenes-dir"):
        bench.default_scenes()
    assert main(["bench", "--scenes-dir", str(tmp_path), "-q"]) == 2
    assert "--scenes-dir" in capsys.readouterr().err
    shutil.copytree(ROOT / "scenes" / "cornell", tmp_path / "scenes" / "cornell")
    assert bench.default_scenes() == [tmp_path / "scenes" / "cornell" / "cornell_path_mis.xml"]


def test_devices_says_whether_each_device_builds(capsys):
    assert main(["devices"]) == 0
    out = capsys.readouterr().out
    assert "builds kernels: yes" in out
