"""3. Delta lights: point and distant lights on a cube and two spheres."""
from ..checks import inside, outward
from ..files import write_obj
from ..geometry import box, rect_xz
from ..plugins import camera_node, diffuse, integrator_node, mesh_obj, microfacet, sampler_node, sphere
from ..xmlnodes import (correct_image, Node, obj_, p_color, p_point, p_transform, p_vector, t_scale, t_translate,
                        write_xml)


DELTA_CAM = dict(origin=(0, 2.6, 7.5), target=(0, 0.5, 0), up=(0, 1, 0), fov=40, width=320, height=240)
DELTA_POINTS = (((-2.5, 3.5, 2.0), (120, 100, 80)), ((2.5, 2.5, 1.5), (40, 60, 90)))
DELTA_DISTANT = dict(direction=(0.4, -1.0, -0.5), irradiance=(1.0, 0.95, 0.85))
DELTA_CUBE = dict(center=(-1.4, 0.5, -0.2), half=(0.5, 0.5, 0.5), rot=30.0)
DELTA_SPHERE_A = ((0.2, 0.65, 0.4), 0.65)
DELTA_SPHERE_T = ((1.8, 0.45, -0.5), 0.45)


def build_delta(out):
    d = out / "delta"
    write_obj(d / "meshes" / "ground.obj", *rect_xz(-8, 8, -8, 8, 0.0, up=True))
    c = DELTA_CUBE
    write_obj(d / "meshes" / "cube.obj", *box(c["center"], c["half"], c["rot"]))
    variants = {
        "direct_ems": (16, True, "direct illumination from two point lights (warm left, cool right) and "
                                 "a distant light (from above, front left, shadows toward the back right): sharp "
                                 "shadows, three shadows per object; sharp highlight on the analytic "
                                 "sphere, broader on the rough blue sphere."),
        "path_mis": (64, True, "the direct_ems image plus indirect light (shadows are not pitch black, "
                               "slight colour bleeding from the red cube onto the ground)."),
        "direct": (16, False, "Nori's 'direct' integrator (point lights only, no distant light): two "
                              "sharp shadows per object; regions seen by neither point light are black."),
    }
    for integ, (spp, with_distant, expect) in variants.items():
        desc = ["Delta lights, integrator '%s'.  A ground plane (diffuse 0.5), a red diffuse cube (left)," % integ,
                "a glossy analytic sphere (microfacet alpha 0.08, middle) and a rough blue tessellated",
                "sphere (microfacet alpha 0.3, right).  Point lights: warm at (-2.5, 3.5, 2), power",
                "(120, 100, 80); cool at (2.5, 2.5, 1.5), power (40, 60, 90)." +
                ("  Distant light: direction" if with_distant else ""),
                ("(0.4, -1, -0.5) (travel direction, normalised by the loader), irradiance (1, 0.95, 0.85)."
                 if with_distant else "No distant light in this variant."),
                "320 x 240, fov 40.", ""] + correct_image(expect)
        children = [integrator_node(integ), sampler_node(spp), camera_node(DELTA_CAM),
                    mesh_obj("meshes/ground.obj", diffuse(0.5)),
                    mesh_obj("meshes/cube.obj", diffuse((0.7, 0.15, 0.1))),
                    sphere(*DELTA_SPHERE_A, microfacet(0.08, (0.2, 0.4, 0.2))),
                    mesh_obj("../meshes/unit_sphere.obj", microfacet(0.3, (0.1, 0.2, 0.6)),
                             to_world=p_transform("toWorld", t_scale(DELTA_SPHERE_T[1]),
                                                  t_translate(DELTA_SPHERE_T[0])))]
        for pos, power in DELTA_POINTS:
            children.append(obj_("emitter", "point", p_point("position", pos), p_color("power", power)))
        if with_distant:
            children.append(obj_("emitter", "distant", p_vector("direction", DELTA_DISTANT["direction"]),
                                 p_color("irradiance", DELTA_DISTANT["irradiance"])))
        write_xml(d / ("delta_%s.xml" % integ), desc, Node("scene", (), children))


def check(out):
    assert inside(DELTA_CAM, [DELTA_CUBE["center"], DELTA_SPHERE_A[0], DELTA_SPHERE_T[0]])
    outward(out / "delta" / "meshes" / "cube.obj", DELTA_CUBE["center"])
