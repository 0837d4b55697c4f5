"""Render tests/emitters/sunsky_twin.xml with Mitsuba 3.9.1 itself and write sunsky_twin.npz beside it, which
test_sunsky.py holds clrender's render to (the format of tests/mitsuba/make_refs.py, whose renderer this uses).

    python tests/emitters/make_sunsky_ref.py [--spp 256] [--seeds 16]

Mitsuba is a development-only tool here (pip install mitsuba==3.9.1, which the sunsky extra installs anyway);
the variant is scalar_rgb (llvm_ad_rgb needs libLLVM and crashed on the machine the reference was made on).
"""
import argparse
import importlib.util
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--seeds", type=int, default=16)
    args = ap.parse_args(argv)
    spec = importlib.util.spec_from_file_location("make_refs", HERE.parent / "mitsuba" / "make_refs.py")
    make_refs = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(make_refs)
    ref = make_refs.render_reference(HERE / "sunsky_twin.xml", args.spp, args.seeds, "scalar_rgb")
    np.savez_compressed(HERE / "sunsky_twin.npz", **ref)
    print(f"sunsky_twin: {int(ref['spp'])} spp, mean {ref['mean'].mean(axis=(0, 1)).round(4)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
