"""7. Analytic spheres under a distantdisk sun and a constant sky."""
import numpy as np

from ..checks import inside, sun_rotation
from ..files import write_obj
from ..geometry import rect_xz, rotation_to, round_vec
from ..plugins import camera_node, diffuse, integrator_node, mesh_obj, microfacet, sampler_node, sphere
from ..xmlnodes import fvec, Node, obj_, p_color, p_float, p_transform, t_rotate, write_xml


SUN_CAM = dict(origin=(0, 2.0, 7.0), target=(0, 0.5, 0), up=(0, 1, 0), fov=40, width=320, height=240)
SUN_DIR = (-0.45, 0.75, 0.5)  # toward the sun
SUN_SPHERES = (((-1.45, 0.6, 0.0), 0.6, "diffuse"), ((0.0, 0.6, 0.0), 0.6, "glossy"),
               ((1.45, 0.6, 0.0), 0.6, "rough"))


def build_sun(out):
    d = out / "sun"
    write_obj(d / "meshes" / "ground.obj", *rect_xz(-20, 20, -20, 20, 0.0, up=True))
    axis, angle = rotation_to(SUN_DIR)
    for integ, spp in (("path_mis", 64), ("direct_mis", 32)):
        desc = ["Analytic spheres under a sun and sky, integrator '%s'." % integ,
                "Three analytic spheres (mesh type 'sphere', radius 0.6) on a diffuse ground (0.5):",
                "left diffuse orange, middle glossy blue microfacet (alpha 0.05), right rough grey",
                "microfacet (alpha 0.3).  Light: a distantdisk sun (thetaA 6 degrees, radiance 50, toward",
                "the upper left in front of the spheres) and a constant bluish sky (extension, radiance",
                "(0.12, 0.15, 0.2)).  320 x 240, fov 40.", "",
                "Correct image: sky-blue background, sunlit spheres with crisp but slightly soft shadows",
                "cast toward the back right, a small bright sun highlight on the glossy sphere, a broad",
                "one on the rough sphere" + ("; indirect light brightens the shadows." if integ == "path_mis"
                                              else "; no interreflection (direct light only).")]
        bs = {"diffuse": diffuse((0.8, 0.35, 0.15)), "glossy": microfacet(0.05, (0.05, 0.1, 0.4)),
              "rough": microfacet(0.3, 0.3)}
        children = [integrator_node(integ), sampler_node(spp), camera_node(SUN_CAM),
                    mesh_obj("meshes/ground.obj", diffuse(0.5))]
        children += [sphere(c, r, bs[k]) for c, r, k in SUN_SPHERES]
        children += [
            obj_("emitter", "distantdisk", p_color("radiance", 50), p_float("thetaA", 6),
                 p_transform("toWorld", t_rotate(round_vec(axis), round(angle, 4))),
                 comment="sun: local +z rotated toward %s (the direction toward the sun)" % fvec(SUN_DIR)),
            obj_("emitter", "constant", p_color("radiance", (0.12, 0.15, 0.2))),
        ]
        write_xml(d / ("sun_%s.xml" % integ), desc, Node("scene", (), children))


def check(out):
    """The spheres are in view and rest on the ground; the sun's rotation points at it."""
    assert inside(SUN_CAM, [np.add(c, (sx * r, 0, 0)) for c, r, _ in SUN_SPHERES for sx in (-1, 1)])
    sun_rotation(SUN_DIR)
    for c, r, _ in SUN_SPHERES:
        assert abs(c[1] - r) < 1e-9
