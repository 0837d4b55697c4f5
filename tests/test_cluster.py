"""Rendering on a real Dask LocalCluster (2 worker processes): the same image as one process however the
work is split, a killed worker's task rerun elsewhere, a failing device reported by name, Ctrl-C and the
time limit keeping true per-pixel counts, and the command line over a running scheduler."""
import json
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

import clrender
from clrender import cluster, cluster_worker
from clrender.renderer import Renderer
from cluster_scene import write_scene

distributed = pytest.importorskip("distributed", reason="the cluster extra (dask[distributed]) is not installed")

SEED = 5


@pytest.fixture(scope="module")
def client():
    lc = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    c = distributed.Client(lc)
    yield c
    c.close()
    lc.close()


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    path = write_scene(tmp_path_factory.mktemp("small"))
    renderer = Renderer(clrender.load_scene(path))
    return path, renderer, renderer.render(spp=12, seed=SEED)


def assert_same_film(film, ref):
    """Per pixel: the same sample counts, and the same sums up to the float32 rounding of their terms."""
    np.testing.assert_array_equal(film.count, ref.count)
    np.testing.assert_array_equal(film.dropped, ref.dropped)
    np.testing.assert_allclose(film.sum_wl, ref.sum_wl, rtol=2e-6, atol=1e-5)
    np.testing.assert_allclose(film.sum_w, ref.sum_w, rtol=2e-6, atol=1e-5)
    np.testing.assert_allclose(film.sum_wl2, ref.sum_wl2, rtol=2e-6, atol=1e-5)
    np.testing.assert_allclose(film.image, ref.image, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("files, tasks, bands", [("ship", None, None), ("ship", 5, 1), ("shared", 7, 3),
                                                 ("ship", 12, 30)])
def test_same_image_as_one_process_however_split(client, small, files, tasks, bands):
    path, _, ref = small
    messages = []
    film = clrender.render(str(path), spp=12, seed=SEED, cluster=client, files=files, tasks=tasks,
                           bands=bands, say=messages.append)
    assert_same_film(film, ref)
    assert film.metadata["spp"] == 12 and film.metadata["interrupted"] is False
    assert film.metadata["bands"] == (bands or 1)


def test_a_scene_object_is_shipped_and_the_seed_matters(client, small):
    path, _, ref = small
    scene = clrender.load_scene(path)
    assert_same_film(clrender.render(scene, spp=12, seed=SEED, cluster=client), ref)
    other = clrender.render(scene, spp=12, seed=SEED + 1, cluster=client, tasks=3)
    assert np.abs(other.sum_wl - ref.sum_wl).max() > 1e-3, "a different seed must give different samples"


def test_the_wavefront_driver_on_workers_gives_the_one_process_image(client, tmp_path):
    """Workers running the wavefront (path_mis here: it runs the path integrators) give the image of one process
    running it, and that of the megakernel up to float rounding (tests/test_wavefront.py)."""
    path = write_scene(tmp_path, integrator="path_mis")
    one = Renderer(clrender.load_scene(path), driver="wavefront").render(spp=6, seed=SEED)
    film = clrender.render(str(path), spp=6, seed=SEED, cluster=client, tasks=3, bands=2, driver="wavefront")
    assert_same_film(film, one)
    mega = Renderer(clrender.load_scene(path), driver="megakernel", reconstruction="sampling").render(spp=6,
                                                                                                      seed=SEED)
    np.testing.assert_allclose(film.image, mega.image, rtol=2e-4, atol=2e-6)


def test_a_shipped_scene_keeps_its_films_reconstruction(client, tmp_path):
    """Workers get the packed tables, not the Scene: a Mitsuba film with sample_border (whose splatting film draws
    samples around the window too, renderer.samples_border) must do so there too, and a box filter's film sample
    the filter, as in one process."""
    from test_splat import scene_xml

    for extra, splat in (('<boolean name="sample_border" value="true"/>', True), ('<rfilter type="box"/>', False)):
        path = tmp_path / f"s{int(splat)}.xml"
        path.write_text(scene_xml(extra, res=12))
        scene = clrender.load_scene(path)
        one = Renderer(scene)
        assert one.splat == splat
        film = clrender.render(scene, spp=4, seed=SEED, cluster=client, tasks=2, bands=2)
        assert (film.metadata.get("film") == "splat") == splat
        np.testing.assert_allclose(film.image, one.render(spp=4, seed=SEED).image, rtol=2e-4, atol=2e-6)


def test_sample_ranges_add_up(client, small):
    path, renderer, ref = small
    a = clrender.render(str(path), spp=5, seed=SEED, cluster=client, tasks=2)
    b = clrender.render(str(path), spp=7, seed=SEED, cluster=client, start_sample=5, tasks=3)
    np.testing.assert_allclose(a.sum_wl + b.sum_wl, ref.sum_wl, rtol=2e-6, atol=1e-5)
    np.testing.assert_array_equal(a.count + b.count, ref.count)


def test_killed_worker_task_is_rerun_and_image_unchanged(client, tmp_path):
    path = write_scene(tmp_path, width=96, height=96)
    ref = Renderer(clrender.load_scene(path)).render(spp=512, seed=SEED)
    pids = client.run(os.getpid)
    seen = {"killed": None, "after": [], "busy": 0}

    def kill_one(result, c):
        if seen["killed"] is None:
            busy = {w: len(keys) for w, keys in c.processing().items() if keys and w in pids}
            if busy:   # a worker in the middle of a task (or with one queued): kill it
                victim = max(busy, key=busy.get)
                os.kill(pids[victim], signal.SIGKILL)
                seen["killed"], seen["busy"] = victim, busy[victim]
        else:
            seen["after"].append(result["worker"])

    film = clrender.render(str(path), spp=512, seed=SEED, cluster=client, tasks=16, on_result=kill_one)
    assert seen["killed"] is not None, "no worker was busy: the test did not kill mid-render"
    assert len(seen["after"]) >= 8, "the kill came too late in the render"
    assert_same_film(film, ref)
    assert film.metadata["tasks"] == 16
    assert seen["killed"] not in client.scheduler_info()["workers"]
    client.wait_for_workers(2, timeout=60)  # the nanny restarts it for the tests that follow


def test_scene_data_lost_with_the_workers_is_sent_again(client, small):
    """Dask keeps a scattered scene on as few as one worker (its memory manager drops the broadcast copies
    no waiting task needs), so a killed worker may take the last copy with it; here every worker dies, so
    it always does. The scene must be sent again to the restarted workers, not the render fail."""
    path, _, ref = small
    pids = client.run(os.getpid)
    killed = []

    def kill_all(result, c):
        if not killed:
            for pid in pids.values():
                os.kill(pid, signal.SIGKILL)
            killed.extend(pids)

    film = clrender.render(str(path), spp=12, seed=SEED, cluster=client, tasks=6, on_result=kill_all)
    assert killed
    assert_same_film(film, ref)
    assert not set(killed) & set(client.scheduler_info()["workers"])
    client.wait_for_workers(2, timeout=60)


def test_failing_device_is_reported_by_name_and_its_task_moves(client, small):
    path, _, ref = small
    victim = sorted(client.scheduler_info()["workers"])[0]

    def break_device():
        os.environ["CLRENDER_DEVICE"] = "no-such-device-xyz"
        cluster_worker._CACHE.clear()

    def repair():
        os.environ.pop("CLRENDER_DEVICE", None)
        cluster_worker._CACHE.clear()

    client.run(break_device, workers=[victim])
    try:
        messages = []
        film = clrender.render(str(path), spp=12, seed=SEED, cluster=client, tasks=6, say=messages.append)
        assert_same_film(film, ref)
        failures = [m for m in messages if "device failure" in m]
        assert failures and victim in failures[0] and "no-such-device-xyz" in failures[0]
        client.run(break_device)   # every device broken: a clear error, not a hang
        with pytest.raises(cluster.ClusterError, match="giving up.*no-such-device-xyz"):
            clrender.render(str(path), spp=12, seed=SEED, cluster=client, tasks=2)
    finally:
        client.run(repair)


def test_ctrl_c_keeps_the_finished_tasks_with_true_counts(client, small):
    path, renderer, _ = small
    done = []

    def press_ctrl_c(result, c):
        done.append(result)
        if len(done) == 3:
            os.kill(os.getpid(), signal.SIGINT)   # the client's handler: cancel the rest, keep these

    film = clrender.render(str(path), spp=24, seed=SEED, cluster=client, tasks=24, on_result=press_ctrl_c)
    assert film.metadata["stopped_by"] == "Ctrl-C" and film.stats.interrupted
    assert 3 <= len(done) < 24 and film.metadata["tasks"] == len(done)
    assert int(film.count.max()) == len(done) == int(film.count.min())   # 1 sample per task, whole film
    # exactly the finished samples: the same as one process rendering those sample indices
    want = sum(renderer.render(spp=1, seed=SEED, start_sample=r["start"]).sum_wl for r in done)
    np.testing.assert_allclose(film.sum_wl, want, rtol=2e-6, atol=1e-5)


def test_partial_films_hold_exactly_the_finished_tasks(client, small):
    """partial=(seconds, cb): while tasks are outstanding, cb gets the film of the tasks finished so far (true
    counts, marked partial); each equals one process rendering exactly those samples."""
    path, renderer, _ = small
    done, snaps = [], []
    film = clrender.render(str(path), spp=6, seed=SEED, cluster=client, tasks=6,
                           on_result=lambda r, c: done.append(r),
                           partial=(0.0, lambda f: snaps.append((f, [r["start"] for r in done]))))
    assert_same_film(film, renderer.render(spp=6, seed=SEED))
    assert "partial" not in film.metadata and snaps
    for snap, starts in snaps:
        assert snap.metadata["partial"] is True and snap.metadata["interrupted"] is True
        assert int(snap.count.min()) == int(snap.count.max()) == len(starts) < 6
        want = sum(renderer.render(spp=1, seed=SEED, start_sample=s).sum_wl for s in starts)
        np.testing.assert_allclose(snap.sum_wl, want, rtol=2e-6, atol=1e-5)


def test_command_line_partial_every_on_a_cluster(client, small, tmp_path, monkeypatch):
    """render --cluster --partial-every: the output holds a part of the finished tasks while the render runs
    (mergeable, true counts), and the whole image at the end."""
    from clrender.cli import main
    from clrender.film import read_exr
    from clrender.parts import read_part

    path, renderer, _ = small
    out = tmp_path / "cl.exr"
    seen = []
    real = cluster.render

    def spy(*a, **k):
        every, cb = k["partial"]

        def wrapped(film):
            cb(film)
            seen.append(read_part(out))
        return real(*a, **{**k, "partial": (every, wrapped)})

    monkeypatch.setattr(cluster, "render", spy)
    assert main(["render", str(path), "--spp", "6", "--seed", str(SEED), "-o", str(out), "-q", "--tasks", "6",
                 "--cluster", client.scheduler.address, "--partial-every", "0.000001"]) == 0
    assert seen and all(0 < int(p.film.count.max()) < 6 and (p.start, p.stop) == (0, 6) for p in seen)
    img, header = read_exr(out)
    np.testing.assert_allclose(img, renderer.render(spp=6, seed=SEED).image, rtol=1e-5, atol=1e-6)
    assert header["clrender.spp"] == "6" and header.get("clrender.kind") != "accumulators"


def test_time_limit_stops_handing_out_tasks(client, small):
    path, _, _ = small
    film = clrender.render(str(path), spp=10**6, seed=SEED, cluster=client, time_limit=1.0)
    assert film.metadata["stopped_by"] == "time limit" and not film.stats.interrupted
    assert 0 < int(film.count.min()) <= int(film.count.max()) < 10**6


def test_command_line_over_a_running_scheduler(client, small, tmp_path, capsys):
    from clrender.cli import main
    from clrender.film import read_exr
    from clrender.parts import read_part

    path, _, ref = small
    out = tmp_path / "cl.exr"
    assert main(["render", str(path), "--spp", "12", "--seed", str(SEED), "-o", str(out), "-q",
                 "--cluster", client.scheduler.address]) == 0
    img, header = read_exr(out)
    np.testing.assert_allclose(img, ref.image, rtol=1e-5, atol=1e-6)
    assert header["clrender.spp"] == "12" and header["clrender.interrupted"] == "False"
    assert (tmp_path / "cl.png").exists()
    # a scheduler file, a sample range: a part that merges like a farm part
    sched = tmp_path / "scheduler.json"
    sched.write_text(json.dumps({"address": client.scheduler.address, "type": "Scheduler"}))
    part = tmp_path / "part.exr"
    assert main(["render", str(path), "--sample-range", "4:8", "--seed", str(SEED), "-o", str(part), "-q",
                 "--cluster", str(sched), "--scene-files", "shared"]) == 0
    p = read_part(part)
    assert (p.start, p.stop) == (4, 12) and (p.film.count == 8).all()
    capsys.readouterr()
    assert main(["render", str(path), "-q", "--cluster", "nowhere"]) == 2
    assert "tcp://HOST:8786" in capsys.readouterr().err


def test_without_dask_the_message_names_the_extra(small):
    path = small[0]
    code = ("import sys; sys.modules['distributed'] = None\n"
            "from clrender.cli import main\n"
            f"sys.exit(main(['render', {str(path)!r}, '-q', '--cluster', 'local:1']))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2, proc.stderr
    assert 'pip install "clrender[cluster]"' in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.slow
def test_ctrl_c_on_the_command_line_with_a_local_cluster(tmp_path):
    """The whole process group gets the SIGINT, as from a terminal: workers included."""
    path = write_scene(tmp_path, width=96, height=96)
    out = tmp_path / "partial.exr"
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "clrender.cli", "render", str(path), "--spp", "1000000",
                             "--cluster", "local:2", "-o", str(out)], stderr=subprocess.PIPE, text=True,
                            env=env, start_new_session=True)
    seen = ""
    while seen.count("sample/s]") < 2:   # the bar moved: a task has finished
        ch = proc.stderr.read(1)
        if not ch:
            break
        seen += ch
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, seen + err
    from clrender.parts import read_part

    p = read_part(out)   # an accumulator EXR: the per-pixel counts of the finished tasks
    assert 0 < int(p.film.count.min()) < 10**6
    assert "partial: Ctrl-C" in err and "Dask dashboard" in seen


def test_shared_scene_files_that_differ_on_a_worker_are_refused(client, small):
    """A worker reading other files than the client's (a stale copy on its filesystem) must not render."""
    from clrender.scenesource import SceneSource

    path = small[0]
    stale = cluster_worker.SharedScene("0" * 32, SceneSource(str(path)))
    f = client.submit(cluster_worker.render_task, stale, 0, (0, 40 * 30), 0, 1, SEED, None, pure=False)
    with pytest.raises(cluster_worker.TaskFailed, match="differ from the client's"):
        f.result()


def test_a_scene_object_is_keyed_the_same_every_time(tmp_path):
    """A shipped scene object is keyed by packed_hash (workers keep its program by the key): packing it again
    must give the same key. The Bsdf rows' bytes that no member covers were left undefined, so it did not."""
    from clrender.pack import pack_scene
    from clrender.scenesource import packed_hash

    scene = clrender.load_scene(write_scene(tmp_path))
    assert len({packed_hash(pack_scene(scene), "path_mis", 40, 30) for _ in range(4)}) == 1
