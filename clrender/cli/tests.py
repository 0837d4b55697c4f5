"""`clrender test` (Nori's ttest/chi2test files) and `clrender warptest` subcommands."""
from __future__ import annotations

import json
import sys
from pathlib import Path


def add_parsers(sub):
    t = sub.add_parser("test", help="run Nori statistical test files (ttest, chi2test)")
    t.add_argument("files", nargs="+", metavar="FILE.xml")
    t.add_argument("--device", help="OpenCL device (index, cpu, gpu or name substring)")
    t.add_argument("--seed", type=int, default=0)
    t.add_argument("--json", metavar="OUT", help="also write the results as JSON ('-' for stdout)")
    t.add_argument("--no-plots", action="store_true", help="do not write histogram PNGs for failing chi2 tests")
    from .options import add_dialect_option

    add_dialect_option(t)
    t.set_defaults(func=cmd_test)
    w = sub.add_parser("warptest", help="chi-square test of one warping function")
    w.add_argument("warp", help="square, tent, disk, triangle, sphere, hemisphere, cosine_hemisphere, cone, beckmann")
    w.add_argument("param", nargs="?", type=float, help="cone half-angle (degrees) or Beckmann alpha")
    w.add_argument("--samples", type=int, default=1_000_000)
    w.add_argument("--device")
    w.add_argument("--seed", type=int, default=0)
    w.add_argument("--plot", metavar="OUT.png", help="histogram image (default: warptest_<warp>.png)")
    w.set_defaults(func=cmd_warptest)


def cmd_test(args) -> int:
    from ..testing.nori import Runner, results_json

    if args.json and args.json != "-":  # before the tests run, not after
        from ..output import check_writable

        check_writable(Path(args.json))
    runner = Runner(device=args.device, seed=args.seed, plots=not args.no_plots, nori_dialect=args.nori_dialect)
    results = []
    for f in args.files:
        print(f"{f}:")
        for r in runner.run_file(f):
            results.append(r)
            print("  " + r.line(), flush=True)
    n_ok = sum(r.passed for r in results)
    n_bad = len(results) - n_ok
    if args.json:
        text = json.dumps(results_json(results), indent=2)
        if args.json == "-":
            print(text)
        else:
            from ..film import _atomic_write

            _atomic_write(Path(args.json), lambda tmp: tmp.write_text(text + "\n"))
    print(f"{n_ok} passed, {n_bad} failed")
    return 0 if n_bad == 0 else 1


def cmd_warptest(args) -> int:
    from ..output import check_writable
    from ..testing.kernels import WARPS
    from ..testing.nori import write_histograms
    from ..testing.warptest import run_warptest

    out = args.plot or f"warptest_{args.warp}.png"
    try:
        if args.warp in WARPS:  # an unknown warp is reported as such, not as an unwritable plot
            check_writable(Path(out))  # before the samples are drawn, not after
        result, obs, exp, p = run_warptest(args.warp, args.param, args.samples, device=args.device, seed=args.seed)
    except ValueError as exc:
        print(f"clrender: error: {exc}", file=sys.stderr)
        return 2
    write_histograms(out, obs, exp, f"{args.warp} {p:g}: {result.message}")
    print(f"{'PASS' if result.passed else 'FAIL'}  warp {args.warp} ({p:g}): {result.message}; histograms: {out}")
    return 0 if result.passed else 1
