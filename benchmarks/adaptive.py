"""Adaptive sampling against uniform sampling and Mitsuba 3: the render time each needs to reach the same relMSE.

    python benchmarks/adaptive.py [--res 128] [--spp 64] [--reference-spp 512] [--repeat 3] [--only NAME ...]
                                  [--film splat|sampling] [--filter gaussian|box] [--json OUT]

Scenes: the twins of benchmarks/vs_mitsuba.py (Cornell box with mirror and glass spheres, the diffuse Cornell box,
the rough plates under four lights, the furnace; not the 1 M-triangle mesh, whose BVH build would dominate a small
run) and our Veach MIS scene (scenes/mis/mis_path_mis.xml, no Mitsuba twin), all at --res (the MIS scene at its
aspect ratio). The twins' box filter (vs_mitsuba.py compares pixels) becomes Mitsuba's default Gaussian in both
renderers' files unless --filter box: the film a user's scene gets, on which splatting differs from filter sampling. Per scene, in one run:
- a reference: clrender, uniform, --reference-spp, another seed; every relMSE below has the reference's own
  expected share, mean(var_ref / (ref^2 + 1e-2)) from its per-pixel variance, taken off;
- the target relMSE R: that of clrender's uniform render at --spp;
- uniform: renders of 4, 8, ... --spp spp, their (render seconds, relMSE), with --film (default: splat, the
  default film, kernels/splat.cl: with a wide filter about a third of the variance per pixel of filter
  sampling), and "uniform_other" the same with the other film;
- adaptive: renders with --film (splat: kernels/splat.cl's store, each pixel's splats weighed by 1 / its count)
  with target errors 0.4, 0.2, 0.1 and 1.5, 1, 0.7 x sqrt(R) (so that a quiet scene's curve
  reaches R too; no promise of R: relMSE is a mean that fireflies dominate, while the target bounds each pixel's
  standard error), max spp 16 x --spp, their (render seconds, including the rounds' host-side tests, mean spp,
  relMSE, rounds; whether it finished as a uniform render, clrender/adaptive.py's switch where the noise is even);
- the potential gain of any per-pixel allocation over uniform sampling, mean(a) / mean(sqrt a)^2 with a the
  reference's relative variance of one sample per pixel: a bound on the samples ratio adaptive allocation can reach
  on the plain relMSE (Cauchy-Schwarz), measured where the estimate of a is best;
- Mitsuba 3 (--variant: llvm_ad_rgb where vs_mitsuba.py finds the libLLVM >= 16 it needs, else scalar_rgb; an
  older libLLVM crashes the process): renders of 4, 8, ... --spp spp.
Our renders are timed --repeat times, interleaved (every uniform and adaptive render once, then again), and each
point takes the median (the shared machine's timings vary 2-3x; the images are the same each time). All of it twice: with relMSE over all pixels, and without the 0.1 % of pixels with the largest errors (a firefly's
pixel dominates the plain mean; adaptive sampling spends samples exactly where fireflies live, so it meets them more
often). Each curve's time (and mean spp) to R is read off it in log-log (between the two points around R; beyond its
ends, error ~ 1 / time from the nearest point). Written to benchmarks/results/adaptive-<date>.json and printed as a
table.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import vs_mitsuba as vm  # noqa: E402  (the twins, their files, Mitsuba's runner, relMSE)

ROOT = Path(__file__).resolve().parents[1]
TWINS = ("cornell_spheres", "cornell", "rough_plates", "furnace")
TARGET_ERRORS = (0.4, 0.2, 0.1)
#: the share of pixels with the largest errors the robust relMSE leaves out (fireflies dominate the plain mean)
OUTLIERS = 1e-3


def corrected_relmse(img, ref, ref_var) -> dict:
    """relMSE of `img` against the reference, less the reference's own expected share: of all pixels ("relmse")
    and without the 0.1 % of pixels with the largest errors ("relmse_robust")."""
    per_pixel = ((img - ref) ** 2 / (ref * ref + 1e-2)).mean(axis=-1)
    own = (ref_var / (ref * ref + 1e-2)).mean(axis=-1)
    keep = per_pixel <= np.quantile(per_pixel, 1.0 - OUTLIERS)
    return {"relmse": float(per_pixel.mean() - own.mean()),
            "relmse_robust": float(per_pixel[keep].mean() - own[keep].mean())}


def time_to(curve, target) -> float:
    """Seconds at which a curve of (seconds, relMSE) points reaches relMSE `target` (log-log interpolation)."""
    pts = sorted((s, e) for s, e in curve if e > 0 and s > 0)
    if not pts or not target > 0:   # an exact image (relMSE <= 0 once the reference's share is off): nothing to read
        return float("nan")
    for (s0, e0), (s1, e1) in zip(pts, pts[1:]):
        if (e0 - target) * (e1 - target) <= 0 and e0 != e1:
            f = np.log(target / e0) / np.log(e1 / e0)
            return float(np.exp(np.log(s0) + f * np.log(s1 / s0)))
    # outside the curve: error ~ 1/time from the nearest end
    s, e = min(pts, key=lambda p: abs(np.log(p[1] / target)))
    return float(s * e / target)


def spp_ladder(top: int) -> list[int]:
    out = [4]
    while out[-1] < top:
        out.append(min(top, out[-1] * 2))
    return out


def potential_gain(ref_film) -> float:
    """mean(a) / mean(sqrt a)^2 over the pixels whose samples vary, a = relative variance of one sample (relMSE's
    channel mean) from the reference's per-pixel variance."""
    n = ref_film.count.astype(np.float64)[..., None]
    a = (ref_film.variance() * n / (ref_film.image.astype(np.float64) ** 2 + 1e-2)).mean(axis=-1)
    a = a[a > 0]
    return float(a.mean() / np.sqrt(a).mean() ** 2) if a.size else 1.0


def bench_scene(name, xml_clr: Path, xml_mi: Path | None, res: int, spp: int, ref_spp: int, say,
                variant: str, repeat: int = 3, film: str = "splat") -> dict:
    import clrender
    from clrender.renderer import Renderer

    scene = clrender.load_scene(xml_clr)
    if name == "veach_mis":
        w, h = scene.width, scene.height
        scene.camera.width, scene.camera.height = res * w // max(w, h), res * h // max(w, h)
    # adaptive and "uniform" with `film`, "uniform_other" with the other one
    other = "sampling" if film == "splat" else "splat"
    r = Renderer(scene, reconstruction=film)
    rs = Renderer(scene, reconstruction=other)
    rs.render(spp=1)
    r.render(spp=1)
    r.render_adaptive(target_error=0.1, max_spp=16)   # the list kernel's first launch, outside the timings
    say(f"{name}: reference, {ref_spp} spp")
    ref_film = r.render(spp=ref_spp, seed=12345)
    ref, ref_var = ref_film.image.astype(np.float64), ref_film.variance()
    out = {"width": r.width, "height": r.height, "potential_gain": potential_gain(ref_film), "film": film,
           "other_film": other, "uniform": [], "uniform_other": [], "adaptive": [], "adaptive_relmse": [],
           "mitsuba": []}
    # the target relMSE (R) first: the adaptive target errors depend on it
    target = corrected_relmse(r.render(spp=spp, seed=7).image, ref, ref_var)["relmse"]
    say(f"{name}: uniform at {spp} spp: relMSE {target:.4g}; uniform and adaptive renders x {repeat}")
    # the fixed targets, and three around sqrt(R) (each pixel at about the uniform render's error)
    errors = sorted({*TARGET_ERRORS, *(round(float(np.sqrt(target)) * k, 4) for k in (1.5, 1.0, 0.7))}, reverse=True)
    runs = [("uniform", s, lambda s=s: r.render(spp=s, seed=7)) for s in spp_ladder(spp)]
    runs += [("uniform_other", s, lambda s=s: rs.render(spp=s, seed=7)) for s in spp_ladder(spp)]
    runs += [(key, e, lambda e=e, a=allocation: r.render_adaptive(target_error=e, max_spp=16 * spp, seed=7,
                                                                   allocation=a))
             for key, allocation in (("adaptive", "error"), ("adaptive_relmse", "relmse")) for e in errors]
    points = [{"seconds_all": []} for _ in runs]
    for rep in range(repeat):
        for (key, x, run), point in zip(runs, points):
            f = run()
            point["seconds_all"].append(f.stats.seconds)
            point["seconds"] = float(np.median(point["seconds_all"]))
            if rep:
                continue
            point.update(corrected_relmse(f.image, ref, ref_var))
            if key in ("uniform", "uniform_other"):
                point["spp"] = x
            else:
                point.update(target_error=x, spp_mean=float(f.count.mean()), converged=f.metadata["converged"],
                             rounds=f.metadata["rounds"],
                             uniform_after=f.metadata.get("uniform_after"),
                             predicted_gain=f.metadata.get("predicted_gain"))
            out[key].append(point)
    if xml_mi is not None:
        say(f"{name}: Mitsuba")
        mi = vm.Mitsuba(xml_mi, variant)
        for s in spp_ladder(spp):
            img, secs = mi.render(s, 7)
            out["mitsuba"].append({"spp": s, "seconds": secs, **corrected_relmse(img, ref, ref_var)})
    for metric in ("relmse", "relmse_robust"):
        target = out["uniform"][-1][metric]
        times = {k: time_to([(p["seconds"], p[metric]) for p in out[k]], target) if out[k] else None
                 for k in ("uniform", "uniform_other", "adaptive", "adaptive_relmse", "mitsuba")}
        # samples (mean spp) to the target: free of the shared machine's timing noise, blind to per-sample costs
        spp = {k: time_to([(p.get("spp_mean", p.get("spp")), p[metric]) for p in out[k]], target)
               for k in ("uniform", "adaptive", "adaptive_relmse")}
        out[metric] = {"target": target, "time_to_target": times, "spp_to_target": spp,
                       "samples_ratio": spp["uniform"] / spp["adaptive"],
                       "relmse_allocation": {"speedup_over_uniform": times["uniform"] / times["adaptive_relmse"],
                                             "samples_ratio": spp["uniform"] / spp["adaptive_relmse"]},
                       "speedup_over_uniform": times["uniform"] / times["adaptive"],
                       # the other film's uniform render against the better adaptive allocation
                       "other_over_best_adaptive": times["uniform_other"] / min(times["adaptive"],
                                                                                times["adaptive_relmse"]),
                       "speedup_over_mitsuba": None if times["mitsuba"] is None
                       else times["mitsuba"] / times["adaptive"]}
    return out


def write_results(kind: str, path, results: dict, **settings) -> Path:
    """`results` with the date, machine, device and `settings` as JSON at `path` (default
    benchmarks/results/KIND-<date>.json)."""
    from clrender.device.context import choose_device

    plat, dev = choose_device(None)
    doc = {"date": dt.datetime.now(dt.timezone.utc).isoformat(), "cpu": vm.cpu_name(),
           "device": f"{plat.name.strip()} / {dev.name.strip()}", **settings, "results": results}
    path = Path(path or ROOT / "benchmarks" / "results" / f"{kind}-{dt.date.today().isoformat()}.json")
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc, indent=1))
    return path


def switched(r) -> str:
    """How many adaptive renders of each allocation finished as uniform ones, e.g. "6/6 0/6"."""
    return " ".join(f"{sum(p.get('uniform_after') is not None for p in r[k])}/{len(r[k])}"
                    for k in ("adaptive", "adaptive_relmse"))


def _commit() -> str | None:
    import subprocess

    try:
        return subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--reference-spp", type=int, default=512)
    ap.add_argument("--repeat", type=int, default=3, help="timings of our renders: the median of this many")
    ap.add_argument("--only", nargs="*", help=f"some of: {', '.join(TWINS)}, veach_mis")
    ap.add_argument("--json", help="default: benchmarks/results/adaptive-<date>.json")
    ap.add_argument("--film", choices=("splat", "sampling"), default="splat",
                    help="the film of the adaptive and uniform renders (the other's uniform renders beside them)")
    ap.add_argument("--filter", choices=("gaussian", "box"), default="gaussian",
                    help="the twins' reconstruction filter (default: Mitsuba's default Gaussian)")
    ap.add_argument("--variant", help="Mitsuba's (default: llvm_ad_rgb with a libLLVM >= 16, else scalar_rgb)")
    a = ap.parse_args(argv)
    say = lambda m: print(f"adaptive: {m}", file=sys.stderr, flush=True)  # noqa: E731
    names = a.only or [*TWINS, "veach_mis"]
    variant = a.variant or ("llvm_ad_rgb" if os.environ.get("DRJIT_LIBLLVM_PATH") else "scalar_rgb")
    results = {}
    load = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            d = Path(tmp) / name
            d.mkdir()
            if name == "veach_mis":
                files = {"clrender": ROOT / "scenes" / "mis" / "mis_path_mis.xml", "mitsuba": None}
            else:
                files = vm.write_twin(vm.TWINS[name](d, a.spp, a.res), d)
                for path in set(files.values()):
                    if a.filter != "box":
                        text = path.read_text()
                        assert '<rfilter type="box"/>' in text, path
                        path.write_text(text.replace('<rfilter type="box"/>', f'<rfilter type="{a.filter}"/>'))
            results[name] = bench_scene(name, files["clrender"], files["mitsuba"], a.res, a.spp, a.reference_spp,
                                        say, variant, a.repeat, a.film)
    path = write_results("adaptive", a.json, results, res=a.res, spp=a.spp, reference_spp=a.reference_spp,
                         repeat=a.repeat, film=a.film, filter=a.filter, mitsuba_variant=variant, load_average_start=load,
                         load_average_end=os.getloadavg(), commit=_commit())
    print(f"{'scene':16} {'size':>8} {'metric':>13} {'target':>9} {'uniform s':>10} {'adaptive s':>10} "
          f"{'mitsuba s':>10} {'vs uniform':>10} {'vs mitsuba':>10} {'spp ratio':>9} {'relmse alloc: time, spp':>24} "
          f"{'bound':>6} {'uniform finish':>14} {'other s':>8} {'best adaptive vs other':>22}")
    for name, r in results.items():
        for metric in ("relmse", "relmse_robust"):
            m = r[metric]
            t = m["time_to_target"]
            mi = "-" if t["mitsuba"] is None else f"{t['mitsuba']:.2f}"
            smi = "-" if m["speedup_over_mitsuba"] is None else f"{m['speedup_over_mitsuba']:.2f}x"
            print(f"{name:16} {r['width']:>4}x{r['height']:<3} {metric:>13} {m['target']:9.4g} {t['uniform']:10.2f} "
                  f"{t['adaptive']:10.2f} {mi:>10} {m['speedup_over_uniform']:9.2f}x {smi:>10} "
                  f"{m['samples_ratio']:8.2f}x {m['relmse_allocation']['speedup_over_uniform']:11.2f}x "
                  f"{m['relmse_allocation']['samples_ratio']:8.2f}x {r['potential_gain']:5.2f}x {switched(r):>14} "
                  f"{t['uniform_other']:8.2f} {m['other_over_best_adaptive']:21.2f}x")
    print(f"wrote {path}", file=sys.stderr)


if __name__ == "__main__":
    t0 = time.perf_counter()
    main()
    print(f"adaptive: {time.perf_counter() - t0:.0f} s", file=sys.stderr)
