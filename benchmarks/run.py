"""Run the default benchmark set on every OpenCL device and keep the result.

    python benchmarks/run.py                      # 64 spp x 5 repeats, all devices
    python benchmarks/run.py --reference-spp 1024 # also render references and plot convergence curves
    python benchmarks/run.py --quick              # 8 spp x 2 repeats, no cold builds (a smoke run)

Writes benchmarks/results/<device-slug>-<date>.json and .png (the devices that can build kernels name the
file) and prints the table. See benchmarks/README.md for how to read and compare the figures.
"""
from __future__ import annotations

import argparse
import datetime as dt
import re
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from clrender import bench  # noqa: E402
from clrender.errors import ClrenderError  # noqa: E402


def slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-")


def render_references(scenes, spp: int, folder: Path, seed: int = 1_000_003) -> list[Path]:
    """A high-spp render of each scene (another seed than the benchmark's) on the default device."""
    from clrender.renderer import Renderer

    out = []
    for s in scenes:
        scene = bench.load_bench_scene(s)[0]
        path = folder / f"{Path(s).stem}_ref{spp}.exr"
        print(f"run.py: reference {path.name} ({spp} spp)", file=sys.stderr, flush=True)
        Renderer(scene).render(spp=spp, seed=seed, progress=True).write_exr(path)
        out.append(path)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--devices", default="all", help="'all' (default) or comma-separated device specs")
    ap.add_argument("--spp", type=int, default=64, help="samples per pixel per repeat (default 64)")
    ap.add_argument("--repeat", type=int, default=5, help="timed repeats (default 5)")
    ap.add_argument("--reference-spp", type=int, default=0,
                    help="render references with this many spp and measure convergence (default: no)")
    ap.add_argument("--out", default=str(HERE / "results"), help="output folder (default benchmarks/results)")
    ap.add_argument("--scenes-dir", default=str(HERE.parent / "scenes"))
    ap.add_argument("--quick", action="store_true", help="8 spp, 2 repeats, no cold builds")
    args = ap.parse_args(argv)
    if args.quick:
        args.spp, args.repeat = 8, 2
    scenes = bench.default_scenes(args.scenes_dir)
    say = (lambda m: print(f"run.py: {m}", file=sys.stderr, flush=True))
    with tempfile.TemporaryDirectory(prefix="clrender-refs-") as tmp:
        refs = render_references(scenes, args.reference_spp, Path(tmp)) if args.reference_spp > 0 else None
        result = bench.run_benchmark(scenes, devices=args.devices, spp=args.spp, repeat=args.repeat,
                                     reference=refs, cold=not args.quick, progress=say)
    for r in result["results"]:  # the temporary reference paths mean nothing later
        if r.get("reference"):
            r["reference"] = f"{Path(r['reference']).name} ({args.reference_spp} spp, seed 1000003)"
    result["settings"]["reference_spp"] = args.reference_spp
    print(bench.format_table(result))
    names = [d["name"] for d in result["devices"] if d["ok"]] or ["no-device"]
    base = Path(args.out) / f"{'+'.join(slug(n) for n in names)}-{dt.date.today().isoformat()}"
    print(f"run.py: wrote {bench.write_json(result, base.with_suffix('.json'))}", file=sys.stderr)
    try:
        print(f"run.py: wrote {bench.plot(result, base.with_suffix('.png'))}", file=sys.stderr)
    except ClrenderError as exc:
        print(f"run.py: no plot: {exc}", file=sys.stderr)
    return 1 if any(r["status"] == "error" for r in result["results"]) else 0


if __name__ == "__main__":
    sys.exit(main())
