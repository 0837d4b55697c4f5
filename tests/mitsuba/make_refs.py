"""Render the Mitsuba twin scenes (tests/mitsuba/scenes/<name>.xml) with Mitsuba 3 itself and write their
references, tests/mitsuba/refs/<name>.npz, which tests/test_mitsuba_twins.py holds clrender's renders to.

    python tests/mitsuba/make_refs.py [name ...] [--spp 1024] [--seeds 16] [--variant llvm_ad_rgb]

Each scene file is read unchanged by Mitsuba. It is rendered ``--seeds`` times with independent seeds at
``--spp`` samples per pixel; the reference is the mean image and its per-pixel standard error (the standard
deviation of the seed images over sqrt(seeds)). A scene without an <integrator> is rendered with Mitsuba's
``path`` (unbounded depth), which is what clrender uses for it. Saved as float32 ``mean`` and ``stderr`` (H x W x 3),
``spp`` (total samples per pixel), ``seeds``, ``variant``, ``mitsuba_version``.

The volume grids some scenes read (scenes/volumes/) are written first by make_volumes.py.

Mitsuba is a development-only tool here: ``pip install mitsuba==3.9.1``. ``llvm_ad_rgb`` (the default; it filters
with the exact reconstruction filter, where ``scalar_rgb`` tabulates it) needs libLLVM, found through
DRJIT_LIBLLVM_PATH (set below when Debian's libLLVM 19 is there).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SCENES = HERE / "scenes"
REFS = HERE / "refs"
LLVM = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"


def render_reference(path: Path, spp: int, seeds: int, variant: str) -> dict:
    if variant.startswith("llvm") and "DRJIT_LIBLLVM_PATH" not in os.environ and Path(LLVM).is_file():
        os.environ["DRJIT_LIBLLVM_PATH"] = LLVM
    import mitsuba as mi

    mi.set_variant(variant)
    scene = mi.load_file(str(path))
    integrator = scene.integrator()
    if integrator is None:
        integrator = mi.load_dict({"type": "path", "max_depth": -1})
    images = []
    for seed in range(seeds):
        img = mi.render(scene, integrator=integrator, spp=spp, seed=seed + 1)
        images.append(np.asarray(img, np.float64)[..., :3])
    stack = np.stack(images)
    mean = stack.mean(axis=0)
    stderr = stack.std(axis=0, ddof=1) / np.sqrt(seeds)
    return dict(mean=mean.astype(np.float32), stderr=stderr.astype(np.float32), spp=np.int64(spp * seeds),
                seeds=np.int64(seeds), variant=np.str_(variant), mitsuba_version=np.str_(mi.__version__))


def main(argv=None) -> int:
    from make_volumes import write_volumes

    write_volumes()   # the grids the scenes read (generated, not committed)
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", help="scene names (default: every scene in tests/mitsuba/scenes)")
    ap.add_argument("--spp", type=int, default=1024, help="samples per pixel of each seed's render")
    ap.add_argument("--seeds", type=int, default=16, help="independent renders averaged")
    ap.add_argument("--variant", default="llvm_ad_rgb", choices=("llvm_ad_rgb", "scalar_rgb"))
    args = ap.parse_args(argv)
    names = args.names or sorted(p.stem for p in SCENES.glob("*.xml"))
    REFS.mkdir(exist_ok=True)
    for name in names:
        path = SCENES / f"{name}.xml"
        if not path.is_file():
            print(f"make_refs: no scene {path}", file=sys.stderr)
            return 1
        t0 = time.perf_counter()
        ref = render_reference(path, args.spp, args.seeds, args.variant)
        out = REFS / f"{name}.npz"
        np.savez_compressed(out, **ref)
        m, e = ref["mean"], ref["stderr"]
        print(f"{name}: {m.shape[1]}x{m.shape[0]}, {int(ref['spp'])} spp, mean {m.mean(axis=(0, 1)).round(4)}, "
              f"median rel. stderr {np.median(e / np.maximum(m, 1e-6)):.4f}, {time.perf_counter() - t0:.1f} s "
              f"-> {out.relative_to(HERE.parents[1])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
