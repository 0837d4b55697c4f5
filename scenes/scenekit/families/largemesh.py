"""6. Large meshes: a displaced geodesic sphere of 1M and 100k triangles (PLYs made on demand)."""
import os
from pathlib import Path

from ..checks import inside, sun_rotation
from ..files import WRITTEN, write_obj, write_ply, write_text
from ..geometry import blob, rect_xz, rotation_to, round_vec
from ..plugins import area, camera_node, diffuse, integrator_node, mesh_obj, mesh_ply, microfacet, sampler_node
from ..xmlnodes import fvec, Node, obj_, p_color, p_float, p_transform, t_rotate, t_translate, write_xml


HERE = Path(__file__).resolve().parents[2]  # scenes/

BLOB_N_LARGE = 224  # 20 * 224^2 = 1,003,520 triangles
BLOB_N_SMALL = 71   # 20 * 71^2 = 100,820 triangles
LARGE_CAM = dict(origin=(0.0, 2.6, 6.5), target=(0, 1.0, 0), up=(0, 1, 0), fov=40, width=320, height=240)
LARGE_SUN_DIR = (-0.5, 0.8, 0.35)  # toward the sun
LARGE_LIGHT = dict(center=(1.5, 3.5, 1.5), half=0.5, radiance=6)


BLOBS = (("1m", BLOB_N_LARGE), ("100k", BLOB_N_SMALL))
# Lowest vertex of each blob below its centre, to 3 decimals (what the XML needs; asserted when meshes are built).
BLOB_LIFT = {"1m": 0.995, "100k": 0.995}


def blob_ply_size(n):
    """(vertices, faces) of the blob with subdivision n (checked before reusing a generated file)."""
    nf = 20 * n * n
    nv = 10 * n * n + 2
    return nv, nf


def write_blob(path, n):
    V, N, F = blob(n)
    lift = -float(V[:, 1].min())
    assert abs(lift - BLOB_LIFT[{BLOB_N_LARGE: "1m", BLOB_N_SMALL: "100k"}[n]]) < 6e-4, lift
    write_ply(path, V, N, F, comment="clrender scenes/build.py: displaced geodesic sphere, %d triangles" % len(F))


def ensure_large_meshes(out=HERE, force=False):
    """Generate the large blob PLYs under out/largemesh/meshes unless a complete one is already there
    (they are tens of MB, so they are generated on demand rather than kept in git). Returns the paths."""
    paths = []
    for tag, n in BLOBS:
        p = Path(out) / "largemesh" / "meshes" / ("blob_%s.ply" % tag)
        paths.append(p)
        if not force and p.is_file():
            nv, nf = blob_ply_size(n)
            with open(p, "rb") as f:
                head = f.read(512)
            if (b"element vertex %d\n" % nv) in head and (b"element face %d\n" % nf) in head:
                end = head.index(b"end_header\n") + len(b"end_header\n")
                if p.stat().st_size == end + 24 * nv + 13 * nf:
                    continue
        p.parent.mkdir(parents=True, exist_ok=True)
        tmp = p.with_name(p.name + ".tmp")
        write_blob(tmp, n)
        WRITTEN.pop()
        os.replace(tmp, p)
    return paths


def build_large(out, meshes=True):
    d = out / "largemesh"
    lift = dict(BLOB_LIFT)
    for tag, n in BLOBS:
        if meshes:
            write_blob(d / "meshes" / ("blob_%s.ply" % tag), n)
        # quoted by clrender's error when the PLY is missing (clrender/shapes/meshfile.py)
        write_text(d / "meshes" / ("blob_%s.ply.missing" % tag),
                   "generated, not kept in git: make it with 'python scenes/build.py --large-meshes' in the clrender "
                   "checkout (or 'python scenes/build.py', which writes every scene)\n")
    write_obj(d / "meshes" / "ground.obj", *rect_xz(-10, 10, -10, 10, 0.0, up=True))
    g = LARGE_LIGHT
    (cx, cy, cz), h = g["center"], g["half"]
    write_obj(d / "meshes" / "light.obj", *rect_xz(cx - h, cx + h, cz - h, cz + h, cy, up=False))
    axis, angle = rotation_to(LARGE_SUN_DIR)

    def scene(integ, spp, tag):
        ly = round(lift[tag], 3) + 0.001  # rests on the ground (lowest vertex 1 mm above it)
        blob_mesh = mesh_ply("meshes/blob_%s.ply" % tag, microfacet(0.15, (0.45, 0.3, 0.2)),
                             to_world=p_transform("toWorld", t_translate((0, ly, 0))))
        return Node("scene", (), [
            integrator_node(integ), sampler_node(spp), camera_node(LARGE_CAM),
            mesh_obj("meshes/ground.obj", diffuse(0.5)),
            blob_mesh,
            mesh_obj("meshes/light.obj", diffuse(0.0), area(g["radiance"]),
                     comment="1 x 1 area light at y = 3.5, front right, normals down"),
            obj_("emitter", "distantdisk", p_color("radiance", 40), p_float("thetaA", 5),
                 p_transform("toWorld", t_rotate(round_vec(axis), round(angle, 4))),
                 comment="sun: cone of 5 degrees about local +z, rotated toward %s" % fvec(LARGE_SUN_DIR)),
        ])

    common = ["A lumpy 'blob' (geodesic sphere displaced along the normal by seeded sinusoids, radius",
              "about 1 +- 0.15, smooth float32 vertex normals, binary little-endian PLY) resting on a",
              "ground plane, lit by a distantdisk sun (thetaA 5, radiance 40, high up, from the left and",
              "slightly in front) and a 1 x 1 area light (front right, radiance 6).  320 x 240, fov 40.",
              "The blob PLYs are not kept in git: running python scenes/build.py generates them."]
    write_xml(d / "largemesh_normals.xml",
              ["Large mesh (1,003,520 triangles), integrator 'normals'."] + common +
              ["", "Correct image: a smooth, bumpy ball coloured by |normal| (green top, red/blue sides),",
               "ground green (0,1,0); no faceting, no holes, no black triangles."],
              scene("normals", 4, "1m"))
    write_xml(d / "largemesh_path_mis.xml",
              ["Large mesh (1,003,520 triangles), integrator 'path_mis'."] + common +
              ["", "Correct image: a brown glossy lumpy ball with a crisp sun shadow on the ground toward",
               "the back right and a soft second shadow toward the back left; smooth shading."],
              scene("path_mis", 64, "1m"))
    write_xml(d / "mesh100k_normals.xml",
              ["~100k-triangle mesh (100,820 triangles), integrator 'normals': the same blob at a lower",
               "resolution (same shape, same file layout)."] + common[1:] +
              ["", "Correct image: as largemesh_normals.xml (very nearly identical)."],
              scene("normals", 4, "100k"))


def check(out):
    assert inside(LARGE_CAM, [(-1.25, 0, 0), (1.25, 0, 0), (0, 2.3, 0), (-1.25, 2.3, 0), (1.25, 2.3, 0)])
    sun_rotation(LARGE_SUN_DIR)
