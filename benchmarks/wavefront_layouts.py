"""Per-stage seconds of the wavefront built in each of its forms: array-of-structures path state (the default),
structure-of-arrays (WF_SOA), the shade stage over 8 or 16 paths per work-item (WF_LANES).

    python benchmarks/wavefront_layouts.py [--twin cornell] [--spp 8] [--res 128] [--rounds 7]
                                           [--forms aos,aos_pad,soa_pad,l8,l16]

Every form renders the same twin of vs_mitsuba.py with every stage waited for (WavefrontExecutor.timed), the forms
taking turns round after round; printed per form and stage: min / median seconds over the rounds (the minimum is
the figure least disturbed by other jobs on a shared machine). benchmarks/README.md, "third step", has a run.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

PAD = {"CLR_VEC3_PASS_IN_MEMORY": None}
FORMS = {"aos": {}, "aos_pad": PAD, "soa_pad": {**PAD, "WF_SOA": None}, "l8": {**PAD, "WF_LANES": 8},
         "l16": {**PAD, "WF_LANES": 16}, "l8_soa": {**PAD, "WF_LANES": 8, "WF_SOA": None}}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--twin", default="cornell")
    ap.add_argument("--spp", type=int, default=8)
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--forms", default="aos,aos_pad,soa_pad,l8,l16")
    args = ap.parse_args(argv)
    import clrender.plugins  # noqa: F401  (registers the plugins)
    from clrender.device.context import choose_device
    from clrender.loader import load_scene
    from clrender.renderer import Renderer
    from vs_mitsuba import made_twins, scene_xml

    forms = args.forms.split(",")
    times = {f: {} for f in forms}
    with tempfile.TemporaryDirectory() as tmp:
        for _name, d, t in made_twins(tmp, [args.twin], args.spp, args.res):
            xml = d / "twin.xml"
            xml.write_text(scene_xml(t, "nori"))
            scene = load_scene(str(xml))
            renderers = {}
            for f in forms:
                renderers[f] = Renderer(scene, driver="wavefront", defines=FORMS[f])
                renderers[f].render(spp=1)   # builds and warms every stage
                renderers[f].executor.timed = True
            for _ in range(args.rounds):
                for f in forms:
                    ex = renderers[f].executor
                    ex.stage_seconds = dict.fromkeys(ex.STAGES, 0.0)
                    t0 = time.perf_counter()
                    renderers[f].render(spp=args.spp)
                    for stage, s in {**ex.stage_seconds, "pass": time.perf_counter() - t0}.items():
                        times[f].setdefault(stage, []).append(s)
    print(f"# {args.twin} {args.res}x{args.res} {args.spp} spp, {args.rounds} rounds, device: {choose_device(None)[1].name}")
    for f in forms:
        print(f, "  ".join(f"{k} {min(x):.3f}/{statistics.median(x):.3f}" for k, x in times[f].items()))


if __name__ == "__main__":
    main()
