"""Render the gallery shown in the README: python docs/make_gallery.py [--out docs] [--spp-scale 1.0]

Each scene renders with its own sampleCount (times --spp-scale) on the default device; the PNGs go to
docs/ and a Markdown table with spp and times to docs/gallery.md.
"""
import argparse
import time
from pathlib import Path

import clrender

HERE = Path(__file__).resolve().parents[1] / "scenes"
GALLERY = [
    ("cornell/cornell_path_mis.xml", "Cornell box, path_mis"),
    ("cornell/cornell_normals.xml", "Cornell box, normals"),
    ("cornell/cornell_ao.xml", "Cornell box, ao"),
    ("mis/mis_direct_ems.xml", "MIS scene, direct_ems"),
    ("mis/mis_direct_mats.xml", "MIS scene, direct_mats"),
    ("mis/mis_direct_mis.xml", "MIS scene, direct_mis"),
    ("mis/mis_path_mis.xml", "MIS scene, path_mis"),
    ("delta/delta_path_mis.xml", "point + distant lights, path_mis"),
    ("glass/glass_path_mis.xml", "glass and caustics, path_mis"),
    ("sun/sun_path_mis.xml", "analytic spheres under distantdisk + sky, path_mis"),
    ("furnace/furnace_path_mis.xml", "furnace (expected 2 everywhere), path_mis"),
    ("largemesh/largemesh_path_mis.xml", "1 M triangles, path_mis"),
    ("mitsuba/showcase.xml", "a Mitsuba 3 scene (rough gold/copper, rough glass, textured roughplastic, blendbsdf; "
                             "spot, disk and constant lights), Mitsuba's path"),
]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default=str(HERE.parent / "docs"))
    ap.add_argument("--spp-scale", type=float, default=1.0)
    ap.add_argument("--only", nargs="*", help="subset of scene paths")
    args = ap.parse_args()
    out = Path(args.out)
    from clrender.bench.discovery import _generate_large_meshes

    _generate_large_meshes(HERE)  # the 1 M-triangle PLY is generated on demand, not kept in git
    rows = []
    for rel, title in GALLERY:
        if args.only and rel not in args.only:
            continue
        t0 = time.perf_counter()
        scene = clrender.load_scene(HERE / rel)
        load = time.perf_counter() - t0
        spp = max(1, round(scene.sample_count * args.spp_scale))
        film = clrender.render(scene, spp=spp, seed=0)
        name = Path(rel).stem + ".png"
        film.write_png(out / name)
        s = film.stats
        rows.append(f"| ![{title}]({name}) | {title} | {scene.width}×{scene.height} | {spp} | "
                    f"{s.seconds:.1f} s | {s.samples / s.seconds / 1e6:.2f} | {load:.1f} s |")
        print(rows[-1], flush=True)
    device = film.metadata["device"]
    (out / "gallery.md").write_text(
        f"Rendered by `python docs/make_gallery.py` on {device} (render time: the sample passes, excluding scene loading, BVH build and kernel compilation).\n\n"
        "| image | scene | size | spp | render | M samples/s | load (XML + meshes) |\n|---|---|---|---|---|---|---|\n"
        + "\n".join(rows) + "\n")


if __name__ == "__main__":
    main()
