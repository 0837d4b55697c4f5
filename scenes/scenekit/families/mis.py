"""2. A Veach-style MIS scene: four plates of growing roughness reflecting four lights of equal power."""
import math

import numpy as np

from ..camera import project
from ..checks import inside
from ..files import write_obj
from ..geometry import normalize, quad, rect_xz
from ..plugins import area, camera_node, diffuse, integrator_node, mesh_obj, microfacet, sampler_node
from ..xmlnodes import correct_image, fnum, Node, p_transform, t_scale, t_translate, write_xml


MIS_CAM = dict(origin=(0, 6.5, 12), target=(0, 2.75, 0), up=(0, 1, 0), fov=45, width=384, height=320)
MIS_LIGHT_Y, MIS_LIGHT_Z = 5.6, -3.4
MIS_LIGHT_X = (-3.75, -1.25, 1.25, 3.75)
MIS_RADII = (0.03, 0.1, 0.3, 0.9)
MIS_POWER_K = 8.0  # radiance = K / r^2  -> every light has power 4 pi^2 K
MIS_ALPHAS = (0.005, 0.02, 0.05, 0.2)  # plate 0 (back, top) .. plate 3 (front, bottom)
MIS_PLATE_CENTERS = ((0, 2.3, -1.6), (0, 1.6, -0.35), (0, 1.0, 0.9), (0, 0.5, 2.15))
MIS_PLATE_HALF = (4.0, 0.6)  # half width (x), half depth
MIS_AMBIENT = dict(center=(0, 9.0, 9.0), half=(6.0, 3.0), radiance=0.6)


def mis_plate(i):
    c = np.array(MIS_PLATE_CENTERS[i], float)
    eye = np.array(MIS_CAM["origin"], float)
    lc = np.array((0.0, MIS_LIGHT_Y, MIS_LIGHT_Z))
    n = normalize(normalize(eye - c) + normalize(lc - c))
    n = normalize(n - np.array([1.0, 0, 0]) * n[0])
    t = normalize(np.cross(np.array([1.0, 0, 0]), n))  # in the y-z plane, perpendicular to n
    hw, hd = MIS_PLATE_HALF
    ex = np.array([hw, 0, 0])
    corners = [c - ex - hd * t, c + ex - hd * t, c + ex + hd * t, c - ex + hd * t]
    return quad(*corners, n), c, n, t


def mis_lights():
    return [((x, MIS_LIGHT_Y, MIS_LIGHT_Z), r, MIS_POWER_K / r ** 2) for x, r in zip(MIS_LIGHT_X, MIS_RADII)]


def build_mis(out):
    d = out / "mis"
    for i in range(4):
        (V, N, F), *_ = mis_plate(i)
        write_obj(d / "meshes" / ("plate%d.obj" % i), V, N, F)
    write_obj(d / "meshes" / "floor.obj", *rect_xz(-12, 12, -8, 14, 0.0, up=True))
    write_obj(d / "meshes" / "back.obj",
              *quad((-12, 0, -8), (12, 0, -8), (12, 12, -8), (-12, 12, -8), (0, 0, 1)))
    a = MIS_AMBIENT
    (cx, cy, cz), (hx, hz) = a["center"], a["half"]
    write_obj(d / "meshes" / "ambient_light.obj", *rect_xz(cx - hx, cx + hx, cz - hz, cz + hz, cy, up=False))

    spp = {"direct_ems": 32, "direct_mats": 32, "direct_mis": 32, "path_mis": 64}
    expect = {
        "direct_ems": "emitter sampling only: highlights of the big lights on the shiny plates are very "
                      "noisy (the smooth top plate is mostly noise), the small lights on the rough bottom "
                      "plate look fine.",
        "direct_mats": "BSDF sampling only: the reflections of the small lights on the rough plates are "
                       "noisy speckles, while the smooth plates show clean reflections.",
        "direct_mis": "MIS: every highlight is clean; the expected image equals direct_ems and direct_mats.",
        "path_mis": "global illumination with MIS: like direct_mis plus interreflection; highlights clean.",
    }
    for integ, n in spp.items():
        desc = [
            "Veach-style multiple importance sampling scene, integrator '%s'." % integ,
            "Four plates (microfacet, kd 0.02, alpha 0.005, 0.02, 0.05, 0.2 from the back/top plate to",
            "the front/bottom plate) each reflect four spherical area lights (tessellated spheres with",
            "outward normals) of radius 0.03, 0.1, 0.3, 0.9 (left to right in the image) and EQUAL power:",
            "radiance = 8 / r^2.  Each plate is tilted so the lights' mirror images fall on it: every",
            "plate shows a row of four highlights, small and sharp on the smooth plates, wide on the",
            "rough ones.  A dim large area light above/behind the camera (radiance 0.6) and a grey floor",
            "and back wall keep the background from being black.  384 x 320, fov 45.",
            "",
        ] + correct_image(expect[integ])
        children = [integrator_node(integ), sampler_node(n), camera_node(MIS_CAM),
                    mesh_obj("meshes/floor.obj", diffuse(0.3)),
                    mesh_obj("meshes/back.obj", diffuse(0.3)),
                    mesh_obj("meshes/ambient_light.obj", diffuse(0.0), area(MIS_AMBIENT["radiance"]),
                             comment="dim ambient light above/behind the camera, normals -y")]
        for i in range(4):
            children.append(mesh_obj("meshes/plate%d.obj" % i, microfacet(MIS_ALPHAS[i], 0.02),
                                     comment="plate %d, alpha %g" % (i, MIS_ALPHAS[i])))
        for (c, r, L) in mis_lights():
            children.append(mesh_obj(
                "../meshes/unit_sphere.obj", diffuse(0.0), area(L),
                to_world=p_transform("toWorld", t_scale(r), t_translate(c)),
                comment="spherical light r = %g, radiance %s (power %s)" % (r, fnum(L),
                                                                          fnum(4 * math.pi ** 2 * r * r * L))))
        write_xml(d / ("mis_%s.xml" % integ), desc, Node("scene", (), children))


def check(out):
    """The mirror image of every light centre on every plate lies on that plate; plates and lights in view;
    plates do not occlude each other along the view of their centres; the lights have equal power."""
    cam = MIS_CAM
    eye = np.array(cam["origin"], float)
    for i in range(4):
        (V, N, F), c, n, t = mis_plate(i)
        assert inside(cam, V, margin=0.02 * cam["width"]), ("plate", i)
        for (lc, r, L) in mis_lights():
            lc = np.array(lc)
            e2 = eye - 2 * np.dot(eye - c, n) * n  # reflected eye
            dd = lc - e2
            s = np.dot(c - e2, n) / np.dot(dd, n)
            hit = e2 + s * dd
            assert 0 < s < 1
            assert abs(hit[0]) < MIS_PLATE_HALF[0] and abs(np.dot(hit - c, t)) < MIS_PLATE_HALF[1], (i, lc)
    for (lc, r, L) in mis_lights():
        assert inside(cam, [np.add(lc, (sx * r, sy * r, 0)) for sx in (-1, 1) for sy in (-1, 1)]), lc
    rows = [project(cam, np.array([mis_plate(i)[1]]))[1][0] for i in range(4)]
    assert rows == sorted(rows)
    powers = [4 * math.pi ** 2 * r * r * L for _, r, L in mis_lights()]
    assert max(powers) - min(powers) < 1e-9 * max(powers)
