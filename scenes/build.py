#!/usr/bin/env python
"""Regenerate every clrender scene (XML) and mesh under scenes/, deterministically.

    python scenes/build.py [--out DIR] [--check]
    python scenes/build.py --large-meshes     # only the large PLY meshes, if missing (they are not in git)

Default output folder: the folder of this script (scenes/).  Everything is generated from code in
scenekit/ (the kit) and scenekit/families/ (one module per scene family), except the hand-written Mitsuba
showcase (mitsuba/showcase.xml, copied as it is); no third-party scene or mesh data.  Fixed float
formatting, a fixed RNG seed, no timestamps: the XML and OBJ output is byte-for-byte reproducible; the
large PLY meshes agree across CPUs to float rounding (numpy's vectorised sin may differ in a last bit), so
they are generated on demand and compared by tolerance (see scenes/README.md).

Conventions used by all scenes
------------------------------
* World space is right-handed, +y is up.  Scenes are written in the *upstream* Nori dialect (wjakob/nori,
  clrender's default), whose camera shows camera +x on the image's left: a plain ``<lookat>`` (whose x
  axis is the viewer's left, cross(up, dir)) gives the unmirrored image.  E.g. the Cornell box camera sits at
  +z looking toward -z: the red wall (x = -1) is on the image's left, the green wall (x = +1) on its right.
* Every emitting mesh has ``vn`` normals pointing toward the part of the scene it lights (area
  emitters emit on the side of the shading normal).  Closed meshes (spheres, boxes) have outward
  normals, except the furnace cube whose normals point inward.
* ``distantdisk``: local +z (mapped by toWorld) is the direction *toward* the light.
  ``distant``: ``direction`` is the direction in which the light travels.
"""
import argparse
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))  # the kit beside this script (tests load this file by path)

from scenekit import files  # noqa: E402
from scenekit.checks import sanity_checks as _sanity_checks  # noqa: E402
from scenekit.families import cornell, delta, furnace, glass, largemesh, mis, mitsuba, shared, sun  # noqa: E402
from scenekit.families.largemesh import ensure_large_meshes  # noqa: E402,F401  (used by tests and clrender bench)

CHECKED = (shared, cornell, mis, delta, glass, furnace, largemesh, sun)


def build(out, large_meshes=True):
    out = Path(out)
    files.WRITTEN.clear()
    shared.build_shared(out)
    cornell.build_cornell(out)
    mis.build_mis(out)
    delta.build_delta(out)
    glass.build_glass(out)
    furnace.build_furnace(out)
    largemesh.build_large(out, large_meshes)
    sun.build_sun(out)
    mitsuba.build_mitsuba(out)
    return sorted(p.relative_to(out).as_posix() for p in files.WRITTEN)


def sanity_checks(out):
    return _sanity_checks(out, CHECKED)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=str(HERE), help="output folder (default: scenes/)")
    ap.add_argument("--check", action="store_true", help="run numerical sanity checks afterwards")
    ap.add_argument("--large-meshes", action="store_true",
                    help="only generate the large PLY meshes (if missing) under --out")
    a = ap.parse_args(argv)
    t0 = time.time()
    if a.large_meshes:
        for p in ensure_large_meshes(a.out):
            print("%s (%.1f MB)" % (p, p.stat().st_size / 1e6))
        return
    files = build(a.out)
    total = sum(os.path.getsize(Path(a.out) / f) for f in files)
    print("wrote %d files (%.1f MB) to %s in %.1f s" % (len(files), total / 1e6, a.out, time.time() - t0))
    if a.check:
        sanity_checks(a.out)
        print("sanity checks passed")


if __name__ == "__main__":
    main()
