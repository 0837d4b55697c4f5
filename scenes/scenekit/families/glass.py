"""4. Glass and caustics: a dielectric sphere and slab under a small area light."""
from ..checks import inside, outward
from ..files import write_obj
from ..geometry import box, quad, rect_xz
from ..plugins import area, camera_node, dielectric, diffuse, integrator_node, mesh_obj, sampler_node, sphere
from ..xmlnodes import correct_image, Node, write_xml


GLASS_CAM = dict(origin=(0, 2.2, 5.5), target=(0, 0.4, 0), up=(0, 1, 0), fov=40, width=320, height=240)
GLASS_LIGHT = dict(center=(-0.4, 3.0, 0.6), half=0.2, radiance=120)
GLASS_SPHERE = ((-0.75, 0.5, 0.0), 0.5)
GLASS_SLAB = dict(center=(0.85, 0.15, 0.25), half=(0.6, 0.15, 0.4), rot=-25.0)


def build_glass(out):
    d = out / "glass"
    write_obj(d / "meshes" / "floor.obj", *rect_xz(-6, 6, -3, 6, 0.0, up=True))
    write_obj(d / "meshes" / "back.obj", *quad((-6, 0, -3), (6, 0, -3), (6, 6, -3), (-6, 6, -3), (0, 0, 1)))
    s = GLASS_SLAB
    write_obj(d / "meshes" / "slab.obj", *box(s["center"], s["half"], s["rot"]))
    g = GLASS_LIGHT
    (cx, cy, cz), h = g["center"], g["half"]
    write_obj(d / "meshes" / "light.obj", *rect_xz(cx - h, cx + h, cz - h, cz + h, cy, up=False))
    for integ, spp, expect in (
            ("path_mis", 256, "a glass sphere (left) and a glass slab (right, box with outward normals) "
                              "on a light floor; the sphere focuses the light into a bright caustic on "
                              "the floor just behind/right of its contact point, the slab casts a "
                              "lighter-edged shadow with caustic fringes; the scene is otherwise dim."),
            ("path_mats", 256, "same expected image as glass_path_mis but far noisier (the 0.4 x 0.4 "
                               "light is only found by BSDF sampling); caustics converge cleaner than "
                               "the directly lit floor.")):
        desc = ["Glass and caustics, integrator '%s'.  Diffuse floor (0.6) and back wall (0.5)," % integ,
                "a dielectric sphere (intIOR 1.5, radius 0.5) and a dielectric slab (1.2 x 0.3 x 0.8),",
                "lit by a small 0.4 x 0.4 area light at y = 3 (normals down, radiance 120).",
                "320 x 240, fov 40.", ""] + correct_image(expect)
        children = [integrator_node(integ), sampler_node(spp), camera_node(GLASS_CAM),
                    mesh_obj("meshes/floor.obj", diffuse(0.6)),
                    mesh_obj("meshes/back.obj", diffuse(0.5)),
                    sphere(*GLASS_SPHERE, dielectric(1.5, 1.0)),
                    mesh_obj("meshes/slab.obj", dielectric(1.5, 1.0)),
                    mesh_obj("meshes/light.obj", diffuse(0.0), area(g["radiance"]))]
        write_xml(d / ("glass_%s.xml" % integ), desc, Node("scene", (), children))


def check(out):
    assert inside(GLASS_CAM, [GLASS_SPHERE[0], GLASS_SLAB["center"]])
    outward(out / "glass" / "meshes" / "slab.obj", GLASS_SLAB["center"])
