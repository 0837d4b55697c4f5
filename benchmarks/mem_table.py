"""Device bytes per triangle, table by table, for large meshes (issue 11: at most 80 B/triangle).

    python benchmarks/mem_table.py [--n 255] [--json benchmarks/results/mem_table-DATE.json]

Packs (clrender.pack.pack_scene, the default 4-wide BVH) a lumpy geodesic sphere of 20 n^2 triangles (n = 255:
1,300,500 triangles, 650,252 shared vertices; scenes/scenekit's ``blob``) alone under a camera, once with its
smooth vertex normals and once without, and the 1 M-triangle largemesh scene (blob, ground, area light) if its
PLY exists. Prints bytes per triangle of every table that is not a single row, and the total (the
``device_bytes`` of SceneBuffers.stats).
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scenes"))

SCENE = """<scene>
    <integrator type="normals"/>
    <camera type="perspective">
        <integer name="width" value="64"/> <integer name="height" value="64"/>
        <transform name="toWorld"> <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/> </transform>
    </camera>
    <mesh type="ply"> <string name="filename" value="blob.ply"/> <bsdf type="diffuse"/> </mesh>
</scene>
"""


def breakdown(scene) -> dict:
    from clrender.pack import pack_scene

    buf = pack_scene(scene)
    nt = buf.stats["triangles"]
    per = {name: a.nbytes / nt for name, a in buf.tables.items() if len(a) > 1}
    per["total"] = buf.stats["device_bytes"] / nt
    return {"triangles": nt, "bytes_per_triangle": per}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=255, help="geodesic subdivision: 20 n^2 triangles (default 255)")
    ap.add_argument("--json", help="also write the numbers here")
    args = ap.parse_args(argv)

    from scenekit.files import write_ply   # scenes/ is on sys.path (above)
    from scenekit.geometry import blob

    from clrender.loader import load_scene
    from clrender.shapes.meshdata import MeshData

    out = {}
    with tempfile.TemporaryDirectory() as d:
        V, N, F = blob(args.n)
        write_ply(Path(d) / "blob.ply", V, N, F)
        (Path(d) / "scene.xml").write_text(SCENE)
        scene = load_scene(Path(d) / "scene.xml")
        out["blob, normals"] = breakdown(scene)
        m = scene.shapes[0].mesh
        scene.shapes[0].mesh = MeshData(m.positions, None, m.uvs, m.faces)
        out["blob, no normals"] = breakdown(scene)
    large = ROOT / "scenes/largemesh/largemesh_path_mis.xml"
    if (large.parent / "meshes/blob_1m.ply").exists():
        out["largemesh_path_mis"] = breakdown(load_scene(large))

    names = []
    for r in out.values():
        names += [k for k in r["bytes_per_triangle"] if k not in names and k != "total"]
    names.append("total")
    print(f"{'bytes/triangle':22s}" + "".join(f"{k[:14]:>15s}" for k in out))
    print(f"{'triangles':22s}" + "".join(f"{r['triangles']:15,d}" for r in out.values()))
    for name in names:
        print(f"{name:22s}" + "".join(f"{r['bytes_per_triangle'].get(name, 0.0):15.2f}" for r in out.values()))
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
