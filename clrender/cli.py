"""Command line: `clrender render | devices` (a thin wrapper over the Python API)."""
from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

from .errors import ClrenderError


def _defines(items):
    out = {}
    for item in items or []:
        if "=" not in item:
            raise ClrenderError(f"-D expects name=value, got '{item}'")
        k, v = item.split("=", 1)
        out[k.strip()] = v
    return out


def cmd_render(args) -> int:
    from .film import Film  # noqa: F401
    from .loader import load_scene
    from .renderer import Interrupted, Renderer

    t0 = time.perf_counter()
    scene = load_scene(args.scene, **_defines(args.define))
    out = Path(args.output) if args.output else Path(args.scene).with_suffix(".exr")
    if out.suffix.lower() != ".exr":
        out = out.with_suffix(".exr")
    renderer = Renderer(scene, device=args.device)
    st = renderer.buffers.stats
    print(f"clrender: {args.scene}: {st['triangles']} triangles, {st['spheres']} spheres, "
          f"{st['emitters']} emitters; BVH {st['bvh_build_seconds']:.2f} s; load {time.perf_counter() - t0:.2f} s; "
          f"device {renderer.device_name}", file=sys.stderr)
    try:
        film = renderer.render(spp=args.spp, seed=args.seed, time_limit=args.time_limit,
                               progress=not args.quiet)
    except Interrupted:
        print("clrender: aborted (second Ctrl-C); nothing written", file=sys.stderr)
        return 130
    film.write_exr(out)
    png = film.write_png(out.with_suffix(".png"))
    s = film.stats
    rate = s.samples / s.seconds / 1e6 if s.seconds > 0 else 0.0
    msg = (f"clrender: wrote {out} and {png}: {film.spp} spp in {s.seconds:.2f} s "
           f"({rate:.2f} M samples/s)")
    if s.interrupted:
        msg += " [interrupted: partial image]"
    if s.dropped:
        msg += f"; {s.dropped} NaN/Inf samples dropped"
    print(msg, file=sys.stderr)
    return 130 if s.interrupted else 0


def cmd_devices(args) -> int:
    from .device.context import choose_device, list_devices

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
    if not devices:
        print("no OpenCL devices found")
        return 1
    print("(* = default; choose with --device INDEX | cpu | gpu | name substring)")
    return 0


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    ap = argparse.ArgumentParser(prog="clrender", description="OpenCL path tracer for Nori XML scenes")
    ap.add_argument("--version", action="version", version=f"clrender {__version__}")
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a scene to EXR (+ PNG)")
    r.add_argument("scene", help="Nori XML scene file")
    r.add_argument("-o", "--output", help="output EXR (default: beside the scene); a PNG is written beside it")
    r.add_argument("--spp", type=int, help="samples per pixel (default: the scene's sampler)")
    r.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    r.add_argument("--device", help="OpenCL device: index, cpu, gpu or name substring (default: PoCL CPU)")
    r.add_argument("--time-limit", type=float, metavar="SEC", help="stop after about SEC seconds")
    r.add_argument("-D", "--define", action="append", metavar="NAME=VALUE", help="set $NAME in the scene")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    r.set_defaults(func=cmd_render)
    d = sub.add_parser("devices", help="list OpenCL platforms and devices")
    d.set_defaults(func=cmd_devices)
    return ap


def main(argv=None) -> int:
    logging.basicConfig(format="clrender: %(message)s", level=logging.WARNING)
    args = build_parser().parse_args(argv)
    if getattr(args, "spp", None) is not None and args.spp < 1:
        print("clrender: error: --spp must be at least 1", file=sys.stderr)
        return 2
    try:
        return args.func(args)
    except ClrenderError as exc:
        print(f"clrender: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("clrender: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
