"""Where the time of a path tracing pass goes: the rays one pass traces, recorded once and cast again alone.

    python benchmarks/profile_pass.py [--repeat 9] [--label NAME] [--json OUT] [--scene XML]

On the Cornell twin of benchmarks/vs_mitsuba.py (mirror and glass spheres, 256x256, path_mis; or --scene),
one pass (one sample per pixel, a fixed sample number, so every repeat does the same work) is recorded with
every BVH query it makes (camera, bounce and shadow rays; kernels/bvh_queries.h BVH_RECORD), in order, per
pixel. Then, interleaved, --repeat times each, one work-item per pixel as in the pass:
- pass:      the render kernel itself (render_pass, 1 spp);
- cast:      the recorded rays only, closest hit or any hit as recorded (traversal + primitive tests);
- boxes:     the same rays with the primitive tests compiled out (BVH_PROFILE_BOXES_ONLY) and tmax = the hit
             found by `cast`, so roughly the same nodes are visited: traversal alone;
- setup:     the pass without its integrator: sampler, filter, camera ray, accumulation.
Shares of the pass (medians): traversal = boxes, primitive tests = cast - boxes, camera/filter/accumulation =
setup, shading + sampling + the integrator's own work = pass - cast - setup. Written to
benchmarks/results/profile_pass-<date>[-label].json and printed.
"""
from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from vs_mitsuba import cpu_name, scene_or_cornell_twin  # noqa: E402

CAP = 64          # recorded rays per pixel (more are counted as dropped; a path that long is very rare)
SAMPLE = 3        # the sample number every timed pass renders


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=9)
    ap.add_argument("--scene", help="a scene XML instead of the Cornell twin")
    ap.add_argument("--label", default="")
    ap.add_argument("--json")
    ap.add_argument("--packets", action="store_true",
                    help="also cast the rays as packets of 8 (the k-th ray of 8 neighbouring pixels; 8-wide BVH only)")
    ap.add_argument("--embree", action="store_true",
                    help="also cast the recorded rays with Embree (embreex, one thread) against the same triangles")
    ap.add_argument("--mitsuba", action="store_true",
                    help="also cast the recorded rays with Mitsuba 3 (llvm_ad_rgb: Embree packets, all cores)")
    ap.add_argument("--visits", action="store_true",
                    help="also count the nodes, leaves and leaf blocks each recorded ray visits (8-wide BVH)")
    ap.add_argument("--bvh", action="append", default=[], metavar="KEY=VALUE",
                    help="a build_bvh option (e.g. traversal_cost=2), for trying builds")
    args = ap.parse_args(argv)

    import pyopencl as cl

    import clrender
    from clrender.device.kernelargs import KernelArgs
    from clrender.device.program import build_program
    from clrender.renderer import LOCAL_SIZE, Renderer

    tmp = tempfile.TemporaryDirectory()
    xml = scene_or_cornell_twin(args.scene, Path(tmp.name))
    scene = clrender.load_scene(xml)
    from clrender.pack import pack_scene

    bvh_options = {k: float(v) if "." in v else int(v) for k, v in (o.split("=", 1) for o in args.bvh)}
    r = Renderer(scene, buffers=pack_scene(scene, bvh_options=bvh_options) if bvh_options else None)
    r.render(spp=1)                       # warm: build + first launch of render_pass
    ctx, queue = r.ctx, r.queue
    n = r.n_pixels
    if n > r.launch_pixels:
        raise SystemExit(f"{xml}: {n} pixels; this tool times one launch per kernel (at most {r.launch_pixels})")
    gsize = (-(-n // LOCAL_SIZE) * LOCAL_SIZE,)
    src = (ROOT / "benchmarks" / "profile_pass.cl").read_text()
    prg = build_program(ctx, src, defines=r.defines)
    prg_boxes = build_program(ctx, src, defines={**r.defines, "BVH_PROFILE_BOXES_ONLY": 1})
    mf = cl.mem_flags
    rw = mf.READ_WRITE
    rec = cl.Buffer(ctx, rw, size=n * CAP * 32)
    kind = cl.Buffer(ctx, rw, size=n * CAP * 4)
    count = cl.Buffer(ctx, rw, size=n * 8)
    hit_t = cl.Buffer(ctx, rw, size=n * CAP * 4)
    out = cl.Buffer(ctx, rw, size=n * 4)
    acc = [cl.Buffer(ctx, rw | mf.COPY_HOST_PTR, hostbuf=np.zeros((n, 4), np.float32)) for _ in range(2)]
    bad = cl.Buffer(ctx, rw | mf.COPY_HOST_PTR, hostbuf=np.zeros(n, np.uint32))
    dummy = cl.Buffer(ctx, rw | mf.COPY_HOST_PTR, hostbuf=np.zeros((1, 4), np.uint32))
    u32 = np.uint32

    k_rec = cl.Kernel(prg, "record_pass")
    KernelArgs(k_rec).set_scene(r._scene_bufs).set(cam=r._camera, filter_cdf=r._filter, rec=rec, kind=kind,
                                                    count=count, cap=u32(CAP), sample=u32(SAMPLE), seed=u32(0))
    cl.enqueue_nd_range_kernel(queue, k_rec, gsize, (LOCAL_SIZE,))
    counts = np.zeros((n, 2), np.uint32)
    cl.enqueue_copy(queue, counts, count)
    kinds = np.zeros(n * CAP, np.uint32)
    cl.enqueue_copy(queue, kinds, kind)
    valid = (np.arange(CAP)[None, :] < counts[:, :1]).reshape(-1)
    n_closest = int(((kinds == 0) & valid).sum())
    n_shadow = int(((kinds == 1) & valid).sum())
    n_camera = int((counts[:, 0] > 0).sum())

    visits = None
    if args.visits:
        if r.buffers.bvh_width != 8:
            raise SystemExit("--visits: counts the 8-wide traversal only")
        vb = cl.Buffer(ctx, rw, size=n * 32)
        k_v = cl.Kernel(build_program(ctx, src, defines={**r.defines, "BVH_COUNT_VISITS": 1}), "count_visits")
        KernelArgs(k_v).set_scene(r._scene_bufs).set(rec=rec, kind=kind, count=count, cap=u32(CAP),
                                                    n_pixels=u32(n), visits=vb)
        cl.enqueue_nd_range_kernel(queue, k_v, gsize, (LOCAL_SIZE,))
        v = np.zeros((n, 2, 4), np.uint32)
        cl.enqueue_copy(queue, v, vb)
        tot = v.astype(np.float64).sum(axis=0)
        visits = {kname: {"rays": int(t[3]), "nodes_per_ray": t[0] / max(t[3], 1),
                          "leaves_per_ray": t[1] / max(t[3], 1), "leaf_blocks_per_ray": t[2] / max(t[3], 1)}
                  for kname, t in (("closest", tot[0]), ("shadow", tot[1]))}

    def cast_kernel(p):
        k = cl.Kernel(p, "cast_rays")
        KernelArgs(k).set_scene(r._scene_bufs).set(rec=rec, kind=kind, count=count, cap=u32(CAP),
                                                   n_pixels=u32(n), hit_t=hit_t, out=out)
        return k

    k_cast, k_boxes = cast_kernel(prg), cast_kernel(prg_boxes)
    k_pass = r.kernel
    r.args.set_scene(r._scene_bufs).set(cam=r._camera, filter_cdf=r._filter, acc0=acc[0], acc1=acc[1], bad=bad,
                                        rays=dummy, pixel_offset=u32(0), pixel_count=u32(n),
                                        sample_offset=u32(SAMPLE), spp=u32(1), seed=u32(0))
    k_setup = cl.Kernel(prg, "setup_pass")
    KernelArgs(k_setup).set(cam=r._camera, filter_cdf=r._filter, acc0=acc[0], acc1=acc[1], sample=u32(SAMPLE),
                            seed=u32(0))
    kernels = {"pass": k_pass, "cast": k_cast, "boxes": k_boxes, "setup": k_setup}
    packets = -(-n // 8)                                    # work-items of cast_packets: 8 pixels each
    gsize8 = (-(-packets // LOCAL_SIZE) * LOCAL_SIZE,)
    if args.packets:
        hit_t8 = cl.Buffer(ctx, rw, size=n * CAP * 4)
        k_pk = cl.Kernel(build_program(ctx, src, defines={**r.defines, "PROFILE_PACKETS": 1}), "cast_packets")
        KernelArgs(k_pk).set_scene(r._scene_bufs).set(rec=rec, kind=kind, count=count, cap=u32(CAP),
                                                      n_pixels=u32(n), hit_t=hit_t8, out=out)
        kernels["packets"] = k_pk
        for name, kname in (("camera rays", "cast_rays"), ("camera packets", "cast_packets")):
            kc = cl.Kernel(build_program(ctx, src, defines={**r.defines, "PROFILE_PACKETS": 1,
                                                            "PROFILE_FIRST_ONLY": 1}), kname)
            KernelArgs(kc).set_scene(r._scene_bufs).set(rec=rec, kind=kind, count=count, cap=u32(CAP),
                                                        n_pixels=u32(n), hit_t=hit_t8, out=out)
            kernels[name] = kc
    # cast first fills hit_t (the boxes-only build reads it); then one untimed launch of each to warm up.
    for name, k in kernels.items():
        cl.enqueue_nd_range_kernel(queue, k, gsize8 if "packets" in name else gsize, (LOCAL_SIZE,))
        queue.finish()
    timed = {name: (lambda k=k, g=(gsize8 if "packets" in name else gsize):
                    (cl.enqueue_nd_range_kernel(queue, k, g, (LOCAL_SIZE,)), queue.finish()))
             for name, k in kernels.items()}
    if args.mitsuba:   # Mitsuba's casts take turns with our kernels, so both see the same machine
        recs = np.zeros((n * CAP, 2, 4), np.float32)
        cl.enqueue_copy(queue, recs, rec)
        mi_calls, mi_info = mitsuba_casts(scene, recs, kinds, valid)
        timed.update(mi_calls)
    times = {name: [] for name in timed}
    load0 = os.getloadavg()
    for _ in range(args.repeat):
        for name, call in timed.items():
            t0 = time.perf_counter()
            call()
            times[name].append(time.perf_counter() - t0)
    med = {k: statistics.median(v) for k, v in times.items()}
    rays = n_closest + n_shadow
    ht = np.zeros(n * CAP, np.float32)
    cl.enqueue_nd_range_kernel(queue, k_cast, gsize, (LOCAL_SIZE,))   # hit_t as cast finds it (boxes rewrote none)
    cl.enqueue_copy(queue, ht, hit_t)
    if args.packets:  # the packets must find what cast_rays found: closest t, and hit / no hit for shadow rays
        h8 = np.zeros(n * CAP, np.float32)
        cl.enqueue_copy(queue, h8, hit_t8)
        cm, sm = valid & (kinds == 0), valid & (kinds == 1)
        agree_c = _agree(h8[cm], ht[cm], 1e-4)
        agree_s = (h8[sm] >= 0) == (ht[sm] >= 0)
        print(f"packets agree with single rays: {agree_c.mean() * 100:.3f} % of closest, "
              f"{agree_s.mean() * 100:.3f} % of shadow rays")
    shares = {
        "traversal (boxes)": med["boxes"],
        "primitive tests (cast - boxes)": med["cast"] - med["boxes"],
        "camera, filter, sampler, accumulation (setup)": med["setup"],
        "shading, sampling, integrator (pass - cast - setup)": med["pass"] - med["cast"] - med["setup"],
    }
    res = {
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "label": args.label, "cpu": cpu_name(), "cores": os.cpu_count(), "device": r.device_name,
        "load_average": [load0, os.getloadavg()],
        "scene": str(xml) if args.scene else "vs_mitsuba cornell_spheres twin (256x256, path_mis)",
        "pixels": n, "sample": SAMPLE, "repeat": args.repeat, "defines": r.defines, "bvh_options": bvh_options,
        "bvh": {k: v for k, v in r.buffers.stats.items() if k.startswith("bvh") or k in ("triangles", "spheres")},
        "rays": {"camera": n_camera, "closest_other": n_closest - n_camera, "shadow": n_shadow, "total": rays,
                 "dropped": int(counts[:, 1].sum()), "per_sample": rays / n},
        "seconds_median": med, "seconds_all": times,
        "cast_rays_per_second": rays / med["cast"], "pass_samples_per_second": n / med["pass"],
        "shares_of_pass": {k: v / med["pass"] for k, v in shares.items()},
    }
    if visits is not None:
        res["visits"] = visits
    if args.embree:
        recs = np.zeros((n * CAP, 2, 4), np.float32)
        cl.enqueue_copy(queue, recs, rec)
        res["embree"] = embree_cast(scene, recs, kinds, valid, ht, args.repeat, res["cores"])
    if args.mitsuba:
        nc, ns = int((valid & (kinds == 0)).sum()), int((valid & (kinds == 1)).sum())
        t_hit = mi_info.pop("t_hit")
        res["mitsuba"] = {**mi_info, "closest_seconds": med["mi closest"], "shadow_seconds": med["mi shadow"],
                          "closest_rays_per_second": nc / med["mi closest"],
                          "shadow_rays_per_second": ns / med["mi shadow"],
                          "rays_per_second": (nc + ns) / (med["mi closest"] + med["mi shadow"]),
                          "closest_hits_agree": float(np.mean(_agree(t_hit, ht[valid & (kinds == 0)])))}
    date = dt.date.today().isoformat()
    path = Path(args.json) if args.json else (
        ROOT / "benchmarks" / "results" / f"profile_pass-{date}{'-' + args.label if args.label else ''}.json")
    path.write_text(json.dumps(res, indent=1) + "\n")
    print(f"{res['scene']}: {rays} rays in one pass ({rays / n:.2f} per sample: {n_camera} camera, "
          f"{n_closest - n_camera} bounce, {n_shadow} shadow; {res['rays']['dropped']} not recorded)")
    print(f"{'kernel':8s} {'median ms':>10s}")
    for k, v in med.items():
        print(f"{k:8s} {v * 1e3:10.2f}")
    print(f"pass {n / med['pass'] / 1e6:.3f} M samples/s; cast alone {rays / med['cast'] / 1e6:.2f} M rays/s")
    for k, v in shares.items():
        print(f"  {v / med['pass'] * 100:5.1f} %  {k}")
    if args.embree:
        e = res["embree"]
        print(f"Embree {e['version']}, 1 thread, on the same rays: {e['rays_per_second'] / 1e6:.2f} M rays/s "
              f"({e['closest_rays_per_second'] / 1e6:.2f} M closest, {e['shadow_rays_per_second'] / 1e6:.2f} M shadow); "
              f"our cast: {rays / med['cast'] / res['cores'] / 1e6:.2f} M rays/s per core "
              f"({res['cores']} cores); hits agree on {e['closest_hits_agree'] * 100:.2f} % of closest rays")
    if visits is not None:
        for kname, v in visits.items():
            print(f"visits per {kname} ray: {v['nodes_per_ray']:.2f} nodes, {v['leaves_per_ray']:.2f} leaves, "
                  f"{v['leaf_blocks_per_ray']:.2f} leaf blocks ({v['rays']} rays)")
    if args.mitsuba:
        m = res["mitsuba"]
        print(f"Mitsuba {m['version']} {m['variant']} ({m['threads']} threads) on the same rays: "
              f"{m['rays_per_second'] / 1e6:.2f} M rays/s ({m['closest_rays_per_second'] / 1e6:.2f} M closest, "
              f"{m['shadow_rays_per_second'] / 1e6:.2f} M shadow); our cast {rays / med['cast'] / 1e6:.2f} M rays/s: "
              f"x{rays / med['cast'] / m['rays_per_second']:.2f}; hits agree on {m['closest_hits_agree'] * 100:.2f} %")
    print(f"-> {path}")


def _scene_triangles(scene, flag: str) -> np.ndarray:
    """(n, 3, 3) float32: every triangle of a scene made only of meshes (the Cornell twin's spheres are meshes)."""
    tris = []
    for sh in scene.shapes:
        m = getattr(sh, "mesh", None)
        if m is None:
            raise SystemExit(f"{flag}: only scenes of triangle meshes")
        tris.append(np.asarray(m.positions, np.float32)[np.asarray(m.faces)])
    return np.concatenate(tris)


def mitsuba_casts(scene, recs, kinds, valid):
    """The recorded rays as Mitsuba 3's llvm_ad_rgb variant casts them against the same triangles: closest-hit rays
    through Scene.ray_intersect_preliminary (hit distance and primitive, no surface record: what our cast does),
    shadow rays through Scene.ray_test, each one wavefront of all the pass's rays of that kind, evaluated and
    waited for (Dr.Jit's own threads, one per core, with Embree's packets inside). Returns the two casts as
    callables for the timing loop (each warmed once: the JIT compiles its kernel then) and what to report,
    with the hit distances (-1 for none) under "t_hit"."""
    import drjit as dr   # importing vs_mitsuba (above) pointed DRJIT_LIBLLVM_PATH at the LLVM it needs
    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")
    tris = _scene_triangles(scene, "--mitsuba")
    nt = len(tris)
    mesh = mi.Mesh("twin", vertex_count=3 * nt, face_count=nt, has_vertex_normals=False)
    params = mi.traverse(mesh)
    params["vertex_positions"] = mi.Float(tris.reshape(-1))
    params["faces"] = mi.UInt32(np.arange(3 * nt, dtype=np.uint32))
    params.update()
    mscene = mi.load_dict({"type": "scene", "twin": mesh})

    def rays(m):
        o, d, tmax = recs[m, 0, :3], recs[m, 1, :3], np.minimum(recs[m, 1, 3], 1e30)
        r = mi.Ray3f(o=mi.Point3f(*(mi.Float(np.ascontiguousarray(o[:, i])) for i in range(3))),
                     d=mi.Vector3f(*(mi.Float(np.ascontiguousarray(d[:, i])) for i in range(3))))
        r.maxt = mi.Float(np.ascontiguousarray(tmax))
        dr.eval(r)
        return r

    closest, shadow = rays(valid & (kinds == 0)), rays(valid & (kinds == 1))

    def run(out):
        dr.eval(out)
        dr.sync_thread()
        return out

    def cast_closest():
        return run(mscene.ray_intersect_preliminary(closest).t)

    def cast_shadow():
        return run(mscene.ray_test(shadow))

    t_hit = np.asarray(cast_closest())
    cast_shadow()
    return ({"mi closest": cast_closest, "mi shadow": cast_shadow},
            {"version": mi.__version__, "variant": "llvm_ad_rgb", "threads": int(dr.thread_count()),
             "t_hit": np.where(np.isfinite(t_hit), t_hit, -1.0),
             "note": "Mitsuba's threads and ours share the same cores, taking turns: compare totals"})


def embree_cast(scene, recs, kinds, valid, ours, repeat, cores) -> dict:
    """The recorded rays (``recs``: per row (o, tmin), (d, tmax); ``kinds``; ``valid`` rows) cast by Embree through
    embreex (rtcIntersect1/rtcOccluded1 per ray, one thread) against the scene's triangles: closest-hit rays as
    INTERSECT, shadow rays as OCCLUDED, each with its tmax. Only triangle scenes (the Cornell twin's spheres are
    meshes). Medians of `repeat`; also how often Embree's hit distance agrees with ``ours`` (cast_rays' hit t per
    row, -1 for none; to 1e-3 relative), a check that both cast the same rays."""
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    es = rtcore_scene.EmbreeScene()
    TriangleMesh(es, np.ascontiguousarray(_scene_triangles(scene, "--embree"), np.float32))
    o, d, tmax = recs[:, 0, :3], recs[:, 1, :3], recs[:, 1, 3]
    closest, shadow = valid & (kinds == 0), valid & (kinds == 1)
    if np.any(recs[valid, 0, 3] != 0.0):
        print("  (some rays have tmin > 0: Embree casts them from 0)")
    sets = {k: (np.ascontiguousarray(o[m]), np.ascontiguousarray(d[m]), np.ascontiguousarray(np.minimum(tmax[m], 1e30)))
            for k, m in (("closest", closest), ("shadow", shadow))}
    times = {"closest": [], "shadow": []}
    for _ in range(repeat):
        for k, (oo, dd, tt) in sets.items():
            t0 = time.perf_counter()
            es.run(oo, dd, dists=tt.copy(), query="INTERSECT" if k == "closest" else "OCCLUDED", output=None)
            times[k].append(time.perf_counter() - t0)
    out = es.run(sets["closest"][0], sets["closest"][1], dists=sets["closest"][2].copy(), output=1)
    med = {k: statistics.median(v) for k, v in times.items()}
    nc, ns = int(closest.sum()), int(shadow.sum())
    return {"version": _embree_version(), "threads": 1,
            "closest_seconds": med["closest"], "shadow_seconds": med["shadow"],
            "closest_rays_per_second": nc / med["closest"], "shadow_rays_per_second": ns / med["shadow"],
            "rays_per_second": (nc + ns) / (med["closest"] + med["shadow"]),
            "closest_hits_agree": float(np.mean(_agree(np.where(out["geomID"] >= 0, out["tfar"], -1.0),
                                                       ours[closest]))),
            "note": f"ours on {cores} cores; Embree one thread: compare per core"}


def _embree_version() -> str:
    """'4 (embreex 4.4.0.post1)': the Embree major version from the library embreex's wheel bundles."""
    import re
    from importlib.metadata import files, version

    libs = [str(f) for f in files("embreex") or () if "libembree" in str(f)]
    m = re.search(r"libembree(\d+)", libs[0]) if libs else None
    return f"{m.group(1) if m else '?'} (embreex {version('embreex')})"


def _agree(a, b, rel=1e-3):
    return np.abs(a - b) <= rel * np.maximum(np.abs(b), 1e-3)


if __name__ == "__main__":
    main()
