"""Cost of rendering through Dask: speed-up of `--cluster local:N` against one process, the overhead of one
task, the cost of sending a task's accumulators back, and what that predicts for 1000 GPU workers.

    python benchmarks/cluster.py                          # cornell path_mis 64 spp; local:1 and local:2
    python benchmarks/cluster.py --spp 128 --workers 1 2 4 --json results/cluster.json
    python benchmarks/cluster.py --gpu-samples-per-second 2e9   # the GPU figure the estimate assumes

Measured (in this order, each on a fresh LocalCluster whose workers have built their programs first, so
the figures are the steady state a long render sees):
  speed-up    the same frame and seed rendered by one process (a warm Renderer) and by local:N
  per task    many tasks of almost no work (an 8x8 film, 1 sample): wall time / tasks = scheduling, the
              call, the result's return and the client's bookkeeping
  per byte    tasks of 1 sample of a 512x512 film (9.4 MB of accumulators each), less their render time
              measured in one process: the cost of moving and adding accumulators
The estimate combines them with a GPU's samples/s (measured on a GPU with `clrender bench`, or assumed).
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

BYTES_PER_PIXEL = 36   # what a task returns per pixel: sum wL, sum w, sum (wL)^2, count (float32) + dropped


def tiny_scene(folder: Path, width: int, height: int) -> Path:
    (folder / "quad.obj").write_text("v -2 -1 -1\nv 2 -1 -1\nv 2 -1 3\nv -2 -1 3\nf 1 2 3 4\n")
    p = folder / f"ao_{width}x{height}.xml"
    p.write_text(f"""<scene><integrator type="ao"/>
  <camera type="perspective"><integer name="width" value="{width}"/><integer name="height" value="{height}"/>
    <float name="fov" value="50"/><transform name="toWorld"><lookat origin="0,1,5" target="0,-0.5,0" up="0,1,0"/></transform>
  </camera>
  <mesh type="obj"><string name="filename" value="quad.obj"/></mesh>
  <mesh type="sphere"><point name="center" value="0,-0.3,0.5"/><float name="radius" value="0.7"/></mesh>
</scene>""")
    return p


def timed(fn, repeat):
    out = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return statistics.median(out), out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", default=str(ROOT / "scenes/cornell/cornell_path_mis.xml"))
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--tasks", type=int, default=200, help="tasks of the per-task measurement")
    ap.add_argument("--gpu-samples-per-second", type=float, default=1e9,
                    help="one GPU worker's speed for the estimate (default 1e9: assumed, see README)")
    ap.add_argument("--json", help="write the figures here")
    args = ap.parse_args(argv)

    import distributed

    import clrender
    from clrender.renderer import Renderer

    os.environ.setdefault("POCL_CACHE_DIR", str(ROOT / ".pocl-cache"))
    say = lambda m: print(m, file=sys.stderr, flush=True)  # noqa: E731
    tmp = Path(tempfile.mkdtemp(prefix="clrender-cluster-bench-"))
    tiny, big = tiny_scene(tmp, 8, 8), tiny_scene(tmp, 512, 512)
    res = {"scene": args.scene, "spp": args.spp, "cpu_count": os.cpu_count(), "loadavg_start": os.getloadavg(),
           "version": clrender.__version__, "dask": distributed.__version__, "local": {}}

    scene = clrender.load_scene(args.scene)
    r = Renderer(scene)
    r.render(spp=1)
    pixels = scene.width * scene.height
    big_r = Renderer(clrender.load_scene(big))
    big_r.render(spp=1)
    big_1spp, _ = timed(lambda: big_r.render(spp=1, seed=1), args.repeat)
    one = lambda: r.render(spp=args.spp, seed=1)  # noqa: E731

    for n in args.workers:
        t0 = time.perf_counter()
        lc = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
        client = distributed.Client(lc)
        start = time.perf_counter() - t0
        try:
            t0 = time.perf_counter()
            clrender.render(args.scene, spp=2, seed=1, cluster=client)          # programs built, scene there
            first = time.perf_counter() - t0
            # interleaved with the one-process render, so both see the same load on this shared machine
            singles, walls = [], []
            for _ in range(args.repeat):
                singles.append(timed(one, 1)[0])
                walls.append(timed(lambda: clrender.render(args.scene, spp=args.spp, seed=1, cluster=client),
                                   1)[0])
            single, wall = statistics.median(singles), statistics.median(walls)
            film = clrender.render(args.scene, spp=args.spp, seed=1, cluster=client)
            clrender.render(str(tiny), spp=4, seed=1, cluster=client, tasks=4)
            per_task, _ = timed(lambda: clrender.render(str(tiny), spp=args.tasks, seed=1, cluster=client,
                                                        tasks=args.tasks), args.repeat)
            per_task /= args.tasks
            k = 6 * n
            clrender.render(str(big), spp=n, seed=1, cluster=client, tasks=n)
            big_wall, _ = timed(lambda: clrender.render(str(big), spp=k, seed=1, cluster=client, tasks=k,
                                                        bands=1), args.repeat)
        finally:
            client.close()
            lc.close()
        nbytes = 512 * 512 * BYTES_PER_PIXEL
        # k tasks on n workers: k/n renders each in parallel; the rest is moving and adding accumulators
        per_big_task = max(big_wall - k / n * big_1spp, 0.0) / k
        row = {"cluster_start_seconds": start, "first_render_seconds": first, "wall_seconds": wall,
               "wall_runs": walls, "single_seconds": single, "single_runs": singles, "speedup": single / wall,
               "tasks": film.metadata["tasks"],
               "per_task_seconds": per_task, "per_task_seconds_9mb": per_big_task,
               "bytes_per_second": nbytes / max(per_big_task - per_task, 1e-9)}
        res["local"][n] = row
        say(f"local:{n}: start {start:.2f} s, first render {first:.2f} s, {args.spp} spp in {wall:.2f} s "
            f"({film.metadata['tasks']} tasks), one process {single:.2f} s "
            f"({pixels * args.spp / single / 1e6:.2f} M samples/s): {row['speedup']:.2f}x; per task "
            f"{per_task * 1e3:.1f} ms (empty), {per_big_task * 1e3:.0f} ms (9.4 MB back) "
            f"-> {row['bytes_per_second'] / 1e6:.0f} MB/s")
    res["loadavg_end"] = os.getloadavg()
    n_best = max(res["local"])
    best = res["local"][n_best]
    res["estimate"] = estimate(best["per_task_seconds"], best["bytes_per_second"], args.gpu_samples_per_second)
    print(format_estimate(res["estimate"]))
    # the same with one band per GPU (bands=1000 in the API): each task renders all its samples of a thin
    # band, so the film comes back about once instead of once per sample chunk
    res["estimate_band_per_gpu"] = estimate(best["per_task_seconds"], best["bytes_per_second"],
                                            args.gpu_samples_per_second, band_pixels=3840 * 2160 // 1000,
                                            tasks_per_gpu=1)
    print("one band per GPU: " + format_estimate(res["estimate_band_per_gpu"]))
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1, default=float))
        say(f"wrote {args.json}")
    return res


def estimate(per_task_s, client_bytes_per_s, gpu_sps, gpus=1000, width=3840, height=2160, spp=65536,
             band_pixels=1 << 16, tasks_per_gpu=2, net_bytes_per_s=1.25e9):
    """A 4K frame at 64k spp on `gpus` workers: compute, plus what the client does serially (schedule each
    task, receive and add each result), with tasks as the cluster module makes them (bands of one launch,
    sample chunks of about equal size)."""
    pixels = width * height
    samples = pixels * spp
    bands = max(1, pixels // band_pixels)
    tasks = max(gpus * tasks_per_gpu, bands)
    chunks = -(-tasks // bands)
    result_bytes = chunks * pixels * BYTES_PER_PIXEL            # every chunk returns the whole film, in bands
    compute = samples / (gpus * gpu_sps)
    schedule = tasks * per_task_s                              # serial on the client/scheduler
    receive = result_bytes / min(client_bytes_per_s, net_bytes_per_s)
    return {"gpus": gpus, "width": width, "height": height, "spp": spp, "gpu_samples_per_second": gpu_sps,
            "samples": samples, "tasks": tasks, "bands": bands, "spp_per_task": spp / chunks,
            "result_bytes": result_bytes, "compute_seconds": compute, "schedule_seconds": schedule,
            "receive_seconds": receive, "total_seconds": max(compute, schedule + receive),
            "efficiency": compute / max(compute, schedule + receive)}


def format_estimate(e):
    return (f"{e['gpus']} GPUs at {e['gpu_samples_per_second']:.2g} samples/s, {e['width']}x{e['height']} at "
            f"{e['spp']} spp = {e['samples']:.3g} samples: compute {e['compute_seconds']:.2f} s; "
            f"{e['tasks']} tasks ({e['bands']} bands x {e['spp_per_task']:.0f} spp) -> scheduling "
            f"{e['schedule_seconds']:.2f} s, {e['result_bytes'] / 1e9:.1f} GB of accumulators back in "
            f"{e['receive_seconds']:.2f} s; frame about {e['total_seconds']:.1f} s "
            f"({100 * e['efficiency']:.0f}% of the ideal)")


if __name__ == "__main__":
    main()
