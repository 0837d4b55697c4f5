"""What in a wavefront stage kernel keeps PoCL's work-item loop scalar, read from PoCL's own intermediate code.

    python benchmarks/pocl_stage_ir.py [--twin cornell] [--stage shade] [--define NAME[=V] ...]

Builds the wavefront program for a twin of vs_mitsuba.py in a fresh PoCL cache with
POCL_LEAVE_KERNEL_COMPILER_TEMP_FILES=1, launches every stage once, and lists, for the stage's kernel, the
instructions LLVM's loop vectoriser refuses: vector- or aggregate-typed values, switches and calls, counted by
kind, in the program PoCL built (program.bc: what our source gives) and in the work-group function after PoCL's
kernel compiler (parallel.bc: what its own passes, e.g. the SLP vectoriser, made of it). Needs llvmlite (a
benchmark-only dependency: pip install llvmlite), which reads PoCL's bitcode. The second step of issue 23 in
benchmarks/README.md was found with this.
"""
from __future__ import annotations

import argparse
import collections
import os
import re
import shutil
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))


def blockers(fn_text: str) -> collections.Counter:
    """Instructions of one function's IR text that the loop vectoriser cannot widen, by kind."""
    kinds = collections.Counter()
    for line in fn_text.splitlines():
        s = line.strip()
        if s.startswith("switch"):
            kinds["switch"] += 1
        elif re.search(r"call [^@]*@(?!llvm\.)", s):
            kinds["call " + re.search(r"@([\w.]+)", s).group(1)] += 1
        else:
            m = re.match(r"%[\w.]+ = (\w+) (?:\w+ )*(<\d+ x \w+>|\{[^}]*\})", s)
            if m and m.group(1) != "getelementptr":
                kinds[f"{m.group(1)} {m.group(2)}"] += 1
    return kinds


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--twin", default="cornell")
    ap.add_argument("--stage", default="shade")
    ap.add_argument("--define", action="append", default=[], help="an extra -D of the program, NAME or NAME=V")
    ap.add_argument("--dump", metavar="DIR", help="write both functions' IR text there (to find what made them)")
    args = ap.parse_args(argv)
    import llvmlite.binding as llvm

    cache = Path(tempfile.mkdtemp(prefix="pocl-ir-"))
    os.environ["POCL_CACHE_DIR"] = str(cache)
    os.environ["POCL_LEAVE_KERNEL_COMPILER_TEMP_FILES"] = "1"
    import pyopencl as cl

    import clrender.plugins  # noqa: F401  (registers the plugins)
    from clrender.device import layout
    from clrender.loader import load_scene
    from clrender.renderer import Renderer
    from vs_mitsuba import made_twins, scene_xml

    defines = dict((d.split("=", 1) + [None])[:2] for d in args.define)
    with tempfile.TemporaryDirectory() as tmp:
        for _name, d, t in made_twins(tmp, [args.twin], 4, 64):
            xml = d / "twin.xml"
            xml.write_text(scene_xml(t, "nori"))
            r = Renderer(load_scene(str(xml)), driver="wavefront", defines=defines)
            dummy = cl.Buffer(r.ctx, cl.mem_flags.READ_WRITE, 64)
            r.executor.bind({n: dummy for n, *_ in layout.FILM_ACCUMULATORS})
            r.executor.warm()
    kernel = f"wf_{args.stage}"
    program = max(cache.glob("*/*/program.bc"), key=lambda p: p.stat().st_size)
    parallel = next(cache.glob(f"*/*/{kernel}/*/parallel.bc"))
    for label, path, pick in (("program.bc (our source, clang -O2)", program, lambda f: f.name == kernel),
                              ("parallel.bc (after PoCL's kernel compiler)", parallel,
                               lambda f: f.name.endswith("_workgroup") and not f.is_declaration)):
        mod = llvm.parse_bitcode(path.read_bytes())
        fn = next(f for f in mod.functions if pick(f))
        kinds = blockers(str(fn))
        if args.dump:
            Path(args.dump).mkdir(parents=True, exist_ok=True)
            (Path(args.dump) / f"{kernel}.{path.stem}.ll").write_text(str(fn))
        print(f"{kernel}, {label}: {sum(kinds.values())} instructions the loop vectoriser refuses")
        for k, n in kinds.most_common(20):
            print(f"  {n:5d}  {k}")
    shutil.rmtree(cache, ignore_errors=True)


if __name__ == "__main__":
    main()
