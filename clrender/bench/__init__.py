"""Cross-device benchmark: ``clrender bench`` and the Python API behind it.

In parts by job: :mod:`.discovery` (which scenes and devices), :mod:`.measure` (the measurements),
:mod:`.report` (JSON, table, compare) and :mod:`.plot`.

    from clrender.bench import run_benchmark, format_table, write_json
    result = run_benchmark(["scenes/cornell/cornell_path_mis.xml"], devices="all", spp=16, repeat=3)
    print(format_table(result)); write_json(result, "bench.json")

For every scene x device this measures, each on its own:

- **build, cold**: building the render program and compiling its one launch shape in a fresh process whose
  ``POCL_CACHE_DIR`` is a new empty folder (PoCL reads its environment once, at initialisation, so only a new
  process gets a cold cache). ``program`` is clBuildProgram; ``first_launch`` is the first enqueue of the
  kernel, where PoCL compiles the work-group function for the launch shape.
- **build, warm**: the same two steps in this process with the disk cache filled, bypassing clrender's
  in-memory program cache (``build_program(..., use_cache=False)``).
- **load** (XML parse + plugin construction, which reads the meshes), **pack** (all tables, including the
  BVH) and **BVH build** (``SceneBuffers.stats``), and the upload of the tables to the device.
- **render**: after one warm-up render (1 spp), ``repeat`` renders of ``spp`` samples per pixel with the same
  seed, so every repetition traces exactly the same rays. From each: samples/s (pixels x spp / seconds),
  time per pass (seconds for one sample in every pixel) and rays/s. We report the median and the spread
  (min, max, quartiles) and keep every repetition's value.
- **rays**: one more render of the same samples with a program built with ``-DCLRENDER_COUNT_RAYS``; the
  kernels count camera rays, other closest-hit (extension) rays and shadow (any-hit) rays. The counts are
  exact for the timed renders (same seed, same samples); rays/s = rays / timed seconds. The timed renders use
  the normal program, which contains no counting code; the counting render's own time is kept as
  ``count_overhead`` (its time over the median).
- **memory**: device bytes (uploaded tables + camera + filter table + per-pixel accumulators) and the host's
  peak resident set size so far (process-wide, so it only grows from row to row).
- **convergence** (with a reference EXR): progressive renders of 1, 1, 2, 4, ... spp (``spp`` in total); after
  each, relMSE = mean over pixels and channels of (x - r)^2 / (r^2 + 1e-2) against render time.
"""
from .discovery import (DEFAULT_SCENES, default_scenes, device_info, find_scenes_dir, load_bench_scene,
                        resolve_devices, scene_hash)
from .measure import (SCHEMA, PreparedScene, bench_one, cold_build, convergence, git_revision, read_exr, relmse,
                      run_benchmark, summarize)
from .plot import plot
from .report import compare, format_compare, format_table, load_json, write_json

__all__ = ["DEFAULT_SCENES", "SCHEMA", "PreparedScene", "bench_one", "cold_build", "compare", "convergence",
           "default_scenes", "device_info", "find_scenes_dir", "format_compare", "format_table", "git_revision",
           "load_bench_scene", "load_json", "plot", "read_exr", "relmse", "resolve_devices", "run_benchmark",
           "scene_hash", "summarize", "write_json"]
