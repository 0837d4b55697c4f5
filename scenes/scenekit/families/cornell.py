"""1. The Cornell box: one scene per integrator, and the default scenes of the README."""
import numpy as np

from ..camera import project
from ..checks import inside
from ..files import read_obj, write_obj
from ..geometry import quad, rect_xz
from ..plugins import area, camera_node, dielectric, diffuse, integrator_node, mesh_obj, sampler_node, sphere
from ..xmlnodes import Node, obj_, write_xml


CBOX_CAM = dict(origin=(0, 1, 4.0), target=(0, 1, 0), up=(0, 1, 0), fov=40, width=256, height=256)
CBOX_LIGHT = (0.5, 1.98)  # side, height
CBOX_WHITE = (0.725, 0.71, 0.68)
CBOX_RED = (0.63, 0.065, 0.05)
CBOX_GREEN = (0.14, 0.45, 0.091)
CBOX_LIGHT_RADIANCE = (17, 17, 17)
CBOX_MIRROR = ((-0.45, 0.35, -0.35), 0.35)
CBOX_GLASS = ((0.45, 0.35, 0.3), 0.35)


def cornell_meshes():
    s, h = CBOX_LIGHT
    return {
        "floor": rect_xz(-1, 1, -1, 1, 0.0, up=True),
        "ceiling": rect_xz(-1, 1, -1, 1, 2.0, up=False),
        "back": quad((-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1), (0, 0, 1)),
        "left": quad((-1, 0, -1), (-1, 0, 1), (-1, 2, 1), (-1, 2, -1), (1, 0, 0)),
        "right": quad((1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1), (-1, 0, 0)),
        "light": rect_xz(-s / 2, s / 2, -s / 2, s / 2, h, up=False),
    }


CBOX_SPP = {"normals": 4, "av": 32, "ao": 32, "direct_ems": 32, "direct_mats": 32, "direct_mis": 32,
            "whitted": 32, "path_mats": 64, "path_ems": 64, "path_mis": 64}

CBOX_EXPECT = {
    "normals": "|shading normal| as colour: floor and ceiling green (0,1,0), back wall blue (0,0,1), side "
               "walls red (1,0,0), light quad green; the spheres show smooth gradients.",
    "av": "average visibility within length 0.5: white on open surfaces, darker toward the box's edges "
          "and corners and around the spheres' contact points.",
    "ao": "ambient occlusion: white in the open, soft darkening in the corners and under the spheres.",
    "direct_ems": "direct light only (emitter sampling): walls lit by the ceiling light, soft shadows of "
                  "the spheres on the floor; the ceiling is black (it only sees the back of the light); "
                  "both spheres (delta BSDFs) are black; the light quad is white.",
    "direct_mats": "direct light only (BSDF sampling): the walls converge to the direct_ems image but are "
                   "much noisier (small light); the ceiling is black; the spheres are black except where "
                   "the sampled mirror/glass direction sees the light (its reflection/refraction).",
    "direct_mis": "direct light only (MIS): the direct_mats image (spheres show only the light's "
                  "reflection/refraction) with low noise; walls identical to direct_ems.",
    "whitted": "direct light on the walls (ceiling black); the left sphere is a perfect mirror reflecting "
               "the lit room, the right sphere refracts it (an inverted view); the glass sphere casts an "
               "ordinary dark shadow (shadow rays do not pass through glass); no caustic, no indirect "
               "light.",
    "path_mats": "global illumination by BSDF sampling only: converges to the path_mis image; noisy, with "
                 "fireflies.",
    "path_ems": "global illumination by emitter sampling (Le counted only after delta bounces): converges "
                "to the path_mis image; the caustic under the glass sphere is noisy.",
    "path_mis": "global illumination with MIS: lit ceiling, colour bleeding (red on the left, green on the "
                "right), the mirror sphere reflects the room, the glass sphere refracts it and focuses a "
                "bright caustic onto the floor.",
}


def cornell_scene(integrator, mesh_prefix, spp=None):
    m = mesh_prefix
    cam = CBOX_CAM
    kw = {"length": 0.5} if integrator == "av" else {}
    children = [
        integrator_node(integrator, **kw),
        sampler_node(spp if spp is not None else CBOX_SPP[integrator]),
        camera_node(cam),
        mesh_obj(m + "floor.obj", diffuse(CBOX_WHITE)),
        mesh_obj(m + "ceiling.obj", diffuse(CBOX_WHITE)),
        mesh_obj(m + "back.obj", diffuse(CBOX_WHITE)),
        mesh_obj(m + "left.obj", diffuse(CBOX_RED), comment="left wall (x = -1, image left): red"),
        mesh_obj(m + "right.obj", diffuse(CBOX_GREEN), comment="right wall (x = +1, image right): green"),
        mesh_obj(m + "light.obj", diffuse(0.0), area(CBOX_LIGHT_RADIANCE),
                 comment="ceiling light, 0.5 x 0.5 at y = 1.98, normals pointing down (-y)"),
        sphere(*CBOX_MIRROR, obj_("bsdf", "mirror"), comment="mirror sphere (back left)"),
        sphere(*CBOX_GLASS, dielectric(1.5, 1.0), comment="glass sphere (front right)"),
    ]
    return Node("scene", (), children)


def cornell_description(integrator, default=False):
    lines = [
        ("clrender default scene: " if default else "") +
        "Cornell box (x in [-1,1], y in [0,2] (y up), z in [-1,1], open toward the camera at +z),",
        "integrator '%s'.  Red wall left, green wall right, white floor/ceiling/back wall," % integrator,
        "a 0.5 x 0.5 area light just below the ceiling (radiance 17), a mirror sphere (back left) and",
        "a glass sphere (front right), analytic spheres of radius 0.35.  256 x 256, fov 40.",
        "",
        "Correct image: " + CBOX_EXPECT[integrator],
    ]
    # wrap the expectation text
    out = []
    for l in lines:
        while len(l) > 100:
            k = l.rfind(" ", 0, 100)
            out.append(l[:k])
            l = "    " + l[k + 1:]
        out.append(l)
    return out


def build_cornell(out):
    d = out / "cornell"
    for name, (V, N, F) in cornell_meshes().items():
        write_obj(d / "meshes" / (name + ".obj"), V, N, F)
    for integ in CBOX_SPP:
        write_xml(d / ("cornell_%s.xml" % integ), cornell_description(integ),
                  cornell_scene(integ, "meshes/"))
    # default scenes (README render command)
    write_xml(out / "default.xml", cornell_description("path_mis", default=True),
              cornell_scene("path_mis", "cornell/meshes/", 64))
    write_xml(out / "default_normals.xml", cornell_description("normals", default=True),
              cornell_scene("normals", "cornell/meshes/", 4))


def check(out):
    """The box opening (front edges) and everything inside are in view, red wall on the left; spheres inside
    the box, not touching walls or each other; wall normals point into the box, the light's down."""
    cam = CBOX_CAM
    assert inside(cam, [(-1, 0, 1), (1, 0, 1), (-1, 2, 1), (1, 2, 1), (-1, 0, -1), (1, 2, -1)])
    px, py, _ = project(cam, np.array([(-1, 1, 0), (1, 1, 0), (0, 0, 0), (0, 2, 0)], float))
    assert px[0] < cam["width"] / 2 < px[1], "red wall (x=-1) must be on the image's left"
    assert py[3] < cam["height"] / 2 < py[2], "ceiling above floor in the image"
    for c, r in (CBOX_MIRROR, CBOX_GLASS):
        c = np.array(c)
        assert np.all(np.abs(c[[0, 2]]) + r < 1) and c[1] - r >= 0 and c[1] + r < CBOX_LIGHT[1]
    assert np.linalg.norm(np.subtract(CBOX_MIRROR[0], CBOX_GLASS[0])) > CBOX_MIRROR[1] + CBOX_GLASS[1]
    for name in ("floor", "ceiling", "back", "left", "right", "light"):
        V, N, F = read_obj(out / "cornell" / "meshes" / (name + ".obj"))
        to_center = np.array([0, 1, 0]) - V
        assert np.all(np.einsum("ij,ij->i", N, to_center) > 0), name
