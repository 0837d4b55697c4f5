"""Command line: the parser, `clrender render | devices | bench`, and how errors and Ctrl-C end the process."""
from __future__ import annotations

import argparse
import logging
import os
import sys
import time

from ..errors import ClrenderError
from ..executors import DRIVERS, RECONSTRUCTIONS, choose_driver
from .options import add_dialect_option, defines, seconds


def cmd_render(args) -> int:
    from ..adaptive import options_from_args
    from ..layers import layers_from_args, needs_features, write_denoised
    from ..loader import load_scene
    from ..output import output_paths
    from ..renderer import Interrupted, Renderer

    options_from_args(args, None)   # adaptive sampling's options with the distributed ones: refused
    layers = layers_from_args(args)
    if args.cluster or args.sample_range:
        if args.emitter_selection != "uniform":   # the workers' scene loading does not take it yet
            print("clrender: error: --emitter-selection power is not supported with --cluster or --sample-range "
                  "yet", file=sys.stderr)
            return 2
        from .distributed import cmd_render_distributed

        return cmd_render_distributed(args, defines(args.define))
    t0 = time.perf_counter()
    out, png = output_paths(args.output, args.scene)  # before any work: an unwritable -o fails now
    scene = load_scene(args.scene, nori_dialect=args.nori_dialect, **defines(args.define))
    if args.emitter_selection == "power":
        if getattr(getattr(scene, "spec", None), "format", "nori") != "mitsuba":
            print(f"clrender: error: {args.scene}: --emitter-selection power is for Mitsuba scenes (a Nori file "
                  "chooses its lights uniformly)", file=sys.stderr)
            return 2
        scene.emitter_selection = "power"
    args.ctrl_c.check()  # a Ctrl-C that a library swallowed still stops us
    adaptive = options_from_args(args, scene)
    try:
        choose_driver(args.driver, scene.integrator.kernel)
    except ClrenderError as e:
        print(f"clrender: error: {args.scene}: --driver: {e}", file=sys.stderr)
        return 2
    try:
        renderer = Renderer(scene, device=args.device, driver=args.driver, feature_aovs=needs_features(args, layers),
                            reconstruction=args.reconstruction)
    except ClrenderError as e:
        print(f"clrender: error: {args.scene}: {e}", file=sys.stderr)
        return 2
    args.ctrl_c.check()
    st = renderer.buffers.stats
    voxels = f"{st['sdf_voxels']} SDF voxels, " if st.get("sdf_voxels") else ""
    print(f"clrender: {args.scene}: {st['triangles']} triangles, {st['spheres']} spheres, {voxels}"
          f"{st['emitters']} emitters; BVH {st['bvh_build_seconds']:.2f} s; load {time.perf_counter() - t0:.2f} s; "
          f"device {renderer.device_name}", file=sys.stderr)
    progress = not args.quiet and (args.progress or sys.stderr.isatty())

    def write_film(film):   # partial images, and the final one
        film.layers = tuple(dict.fromkeys(film.layers + layers))
        film.write(out)
        if png is not None:
            film.write_png(png)

    partial = None if args.partial_every is None else (args.partial_every, write_film)
    try:
        if adaptive is not None:
            film = renderer.render_adaptive(adaptive.target_error, adaptive.min_spp, adaptive.max_spp, seed=args.seed,
                                            time_limit=args.time_limit, progress=progress, partial=partial,
                                            allocation=adaptive.allocation, uniform_below=adaptive.uniform_below)
        else:
            film = renderer.render(spp=args.spp, seed=args.seed, time_limit=args.time_limit, progress=progress,
                                   partial=partial)
    except Interrupted:
        print("clrender: aborted (second Ctrl-C); nothing written", file=sys.stderr)
        _exit_now(args, 130)
        return 130
    if getattr(scene, "aovs", None) and not film.stats.interrupted:   # an aov's channels beside the image
        from ..renderer import aov_channels

        film.aovs = aov_channels(scene, spp=film.spp, seed=args.seed, device=args.device, driver=args.driver)
    write_film(film)   # the whole image now
    if args.denoise:
        d_exr, _ = write_denoised(film, out)
        print(f"clrender: wrote {d_exr} and its PNG (denoised in {film.metadata['denoise_seconds']:.2f} s)",
              file=sys.stderr)
    s = film.stats
    rate = s.samples / s.seconds / 1e6 if s.seconds > 0 else 0.0
    msg = (f"clrender: wrote {out}{f' and {png}' if png is not None else ''}: {film.spp} spp in {s.seconds:.2f} s "
           f"({rate:.2f} M samples/s)")
    if adaptive is not None:
        msg += (f"; adaptive: {film.metadata['spp_mean']:.1f} spp on average, {film.metadata['converged']:.1%} of "
                f"the pixels within {adaptive.target_error:g}")
        if "uniform_after" in film.metadata:
            msg += (f" (even noise: uniform from {film.metadata['uniform_after']} spp, potential gain "
                    f"{film.metadata['predicted_gain']:.2f})")
    if s.interrupted:
        msg += " [interrupted: partial image]"
    if s.dropped:
        msg += f"; {s.dropped} NaN/Inf samples dropped"
    print(msg, file=sys.stderr)
    code = 130 if s.interrupted else 0
    _exit_written(args, code)
    return code


def _exit_now(args, code: int) -> None:
    """Leave at once, without waiting for device work in flight (only when run as a program)."""
    if getattr(args, "hard_exit", False):
        sys.stderr.flush()
        sys.stdout.flush()
        os._exit(code)


def _exit_written(args, code: int) -> None:
    """Everything is written: leave without the interpreter's and the OpenCL driver's teardown (0.1-0.2 s of
    freeing what the process is about to lose anyway), unless a profiler or coverage tool, which writes its
    report at exit, is watching."""
    if sys.gettrace() is None and sys.getprofile() is None and "coverage" not in sys.modules:
        _exit_now(args, code)


def cmd_devices(args) -> int:
    from ..device.context import build_check, choose_device, list_devices

    devices = list_devices()
    try:
        default = choose_device(None)
    except ClrenderError:
        default = None
    for i, (p, d) in enumerate(devices):
        mark = "*" if default is not None and d.int_ptr == default[1].int_ptr else " "
        print(f"{mark}[{i}] {p.name.strip()} / {d.name.strip()}")
        print(f"      {d.version.strip()}; {d.opencl_c_version.strip()}; driver {d.driver_version.strip()}")
        print(f"      {d.max_compute_units} compute units, {d.global_mem_size / 2**30:.1f} GiB global memory, "
              f"max work-group {d.max_work_group_size}")
        why = build_check(p, d)
        print("      builds kernels: yes" if why is None else f"      builds kernels: NO ({why})")
    from ..device import intel_cpu

    if (intel_cpu.state or {}).get("problem"):
        print(f"Intel's OpenCL CPU runtime is not listed: {intel_cpu.state['problem']}")
    if not devices:
        print("no OpenCL devices found")
        return 1
    print("(* = default; choose with --device INDEX | cpu | gpu | intel | name substring)")
    return 0


def cmd_bench(args) -> int:
    import os

    from .. import bench
    from ..scene.dialect import ENV_VAR, resolve

    if args.nori_dialect:  # through the environment, so the cold-build child process reads the same
        os.environ[ENV_VAR] = resolve(args.nori_dialect)

    if args.compare:
        if args.scenes:
            raise ClrenderError("--compare takes two JSON files and no scenes")
        a, b = (bench.load_json(p) for p in args.compare)
        print(bench.format_compare(a, b, args.compare[0], args.compare[1]))
        return 0
    for name in ("spp", "repeat", "width", "height"):
        v = getattr(args, name)
        if v is not None and v < 1:
            raise ClrenderError(f"--{name} must be at least 1")
    if args.plot:  # fail before measuring, not after
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            raise ClrenderError('--plot needs matplotlib: pip install "clrender[plot]"') from None
    say = None if args.quiet else (lambda msg: print(f"clrender bench: {msg}", file=sys.stderr, flush=True))
    result = bench.run_benchmark(args.scenes or None, devices=args.devices, integrator=args.integrator,
                                 spp=args.spp, repeat=args.repeat, width=args.width, height=args.height,
                                 seed=args.seed, reference=args.reference, cold=not args.no_cold,
                                 scenes_dir=args.scenes_dir, progress=say, driver=args.driver)
    print(bench.format_table(result))
    if args.json:
        print(f"clrender bench: wrote {bench.write_json(result, args.json)}", file=sys.stderr)
    if args.plot:
        print(f"clrender bench: wrote {bench.plot(result, args.plot)}", file=sys.stderr)
    bad = [r for r in result["results"] if r["status"] == "error"]
    return 1 if bad else 0


def build_parser() -> argparse.ArgumentParser:
    from ..version import __version__

    ap = argparse.ArgumentParser(prog="clrender", description="OpenCL path tracer for Nori and Mitsuba 3 XML scenes")
    ap.add_argument("--version", action="version", version=f"clrender {__version__}")
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a scene to EXR (+ PNG)")
    r.add_argument("scene", help="scene file: Nori XML, or Mitsuba 3 XML (root <scene version=...>)")
    r.add_argument("-o", "--output", help="output .exr file (a PNG preview is written beside it), or a folder "
                                          "(default: beside the scene); or a .png, .jpg, .hdr or .pfm file: that "
                                          "format alone")
    r.add_argument("--spp", type=int, help="samples per pixel (default: the scene's sampler)")
    r.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    r.add_argument("--device", help="OpenCL device: index, cpu, gpu or name substring (default: PoCL CPU)")
    r.add_argument("--time-limit", type=seconds, metavar="SEC", help="stop after about SEC seconds")
    r.add_argument("--partial-every", type=seconds, metavar="SEC",
                   help="while rendering, write the image so far over the output every SEC seconds (atomically, "
                        "its EXR metadata giving the samples done), to look at a long render or keep its work if "
                        "the process dies")
    r.add_argument("--driver", choices=DRIVERS, default="auto",
                   help="how passes run: the megakernel, or the wavefront's stage kernels (path integrators); "
                        "auto: the faster (today the megakernel)")
    r.add_argument("--reconstruction", choices=RECONSTRUCTIONS, default="auto",
                   help="how the film makes pixels of samples: splat (as Mitsuba and Nori: each sample, placed "
                        "uniformly in its pixel, weighted into every pixel within the filter's radius), sampling "
                        "(filter importance sampling: each sample in one pixel, more noise with a wide filter), "
                        "auto (default: splat, except --driver wavefront, box filters and feature AOVs)")
    r.add_argument("-D", "--define", action="append", metavar="NAME=VALUE", help="set $NAME in the scene")
    r.add_argument("--emitter-selection", choices=("uniform", "power"), default="uniform",
                   help="how light sampling picks an emitter in a Mitsuba scene: uniformly (default, as Mitsuba) or "
                        "in proportion to each emitter's power")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    r.add_argument("--progress", action="store_true",
                   help="show the progress bar even when stderr is not a terminal (e.g. a log file)")
    add_dialect_option(r)
    from ..adaptive import add_render_arguments as add_adaptive_arguments
    from ..layers import add_render_arguments as add_layer_arguments
    from .distributed import add_merge_parser, add_render_arguments

    add_render_arguments(r)
    add_adaptive_arguments(r)
    add_layer_arguments(r)
    r.set_defaults(func=cmd_render)
    d = sub.add_parser("devices", help="list OpenCL platforms and devices")
    d.set_defaults(func=cmd_devices)
    from .tests import add_parsers

    add_parsers(sub)
    add_merge_parser(sub)
    b = sub.add_parser("bench", help="benchmark scenes on OpenCL devices (or --compare two results)",
                       description="Measure build, load, BVH, render speed (samples/s, rays/s), memory and, "
                                   "with --reference, convergence, per scene and device. Without SCENE: the "
                                   "default set from the repository's scenes/ folder.")
    b.add_argument("scenes", nargs="*", metavar="SCENE", help="Nori XML scene files (default: the default set)")
    b.add_argument("--devices", metavar="all|SPEC,...",
                   help="'all', or comma-separated device specs as --device takes (default: the default device)")
    b.add_argument("--integrator", metavar="NAME", help="render with this integrator instead of the scene's")
    b.add_argument("--driver", choices=DRIVERS, default="auto",
                   help="how passes run: megakernel or wavefront (path integrators); rays are counted by the megakernel")
    b.add_argument("--spp", type=int, default=16, help="samples per pixel per repetition (default 16)")
    b.add_argument("--repeat", type=int, default=3, help="timed repetitions after the warm-up (default 3)")
    b.add_argument("--width", type=int, help="override the image width")
    b.add_argument("--height", type=int, help="override the image height")
    b.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    b.add_argument("--reference", action="append", metavar="REF.exr",
                   help="reference image for a relMSE convergence curve (one per scene, in order)")
    b.add_argument("--json", metavar="OUT", help="write all figures as JSON")
    b.add_argument("--plot", metavar="OUT.png", help="write a plot (needs matplotlib: clrender[plot])")
    b.add_argument("--compare", nargs=2, metavar=("A.json", "B.json"), help="print ratios B/A of two results")
    b.add_argument("--scenes-dir", help="where the default set lives (default: ./scenes or a parent's)")
    b.add_argument("--no-cold", action="store_true", help="skip the cold-build subprocess")
    b.add_argument("-q", "--quiet", action="store_true", help="no progress messages")
    add_dialect_option(b)
    b.set_defaults(func=cmd_bench)
    return ap


def main(argv=None) -> int:
    if argv is None:
        # Run as a program: numpy's OpenBLAS would start a thread per core when numpy is imported (tens of ms) and
        # spin it after every small product, on cores PoCL renders with; our BLAS work is 4x4 transforms. An
        # OPENBLAS_NUM_THREADS the user set wins.
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    from ..interrupt import CtrlC

    # From the start: a Ctrl-C during the first imports must not be swallowed by a library's import guard.
    with CtrlC() as ctrl_c:
        try:
            return _main(argv, ctrl_c)
        except KeyboardInterrupt:
            # before the command started (building the parser, parsing): nothing to save
            print("clrender: interrupted", file=sys.stderr)
            return 130


def _main(argv, ctrl_c) -> int:
    logging.basicConfig(format="clrender: %(message)s", level=logging.WARNING)
    args = build_parser().parse_args(argv)
    args.ctrl_c = ctrl_c
    if getattr(args, "spp", None) is not None and not 1 <= args.spp < 2**32:
        print("clrender: error: --spp must be between 1 and 4294967295", file=sys.stderr)
        return 2
    if args.command == "render" and not 0 <= args.seed < 2**32:
        print("clrender: error: --seed must be between 0 and 4294967295", file=sys.stderr)
        return 2
    args.hard_exit = argv is None  # run as a program (not called from Python): may leave with os._exit
    try:
        return args.func(args)
    except KeyboardInterrupt:
        return _interrupted(args)
    except Exception as exc:
        if ctrl_c.pressed:
            # A library turned our KeyboardInterrupt into some other error: the cause is the Ctrl-C.
            return _interrupted(args)
        code = _report(exc)
        if code is None:
            raise
        return code


def _interrupted(args) -> int:
    print("clrender: interrupted", file=sys.stderr)
    _exit_now(args, 130)
    return 130


def _report(exc: Exception) -> int | None:
    """Print an error a user can act on and return the exit status; None for a bug (a traceback)."""
    if isinstance(exc, ClrenderError):
        print(f"clrender: error: {exc}", file=sys.stderr)
        return 2
    if isinstance(exc, OSError):  # a full disk, ...
        print(f"clrender: error: {exc}", file=sys.stderr)
        return 2
    if isinstance(exc, MemoryError):
        print("clrender: error: out of memory (try a smaller width/height or scene)", file=sys.stderr)
        return 2
    if type(exc).__module__.startswith("pyopencl"):
        # The OpenCL driver failed (out of device memory, a lost device, a driver bug): say so plainly.
        print(f"clrender: OpenCL error on the device: {exc}", file=sys.stderr)
        return 3
    return None
