"""5. Furnace tests: closed emitting cube and a sphere under a constant environment (analytic answers)."""
import numpy as np

from ..files import read_obj, write_obj
from ..geometry import box
from ..plugins import area, camera_node, diffuse, integrator_node, mesh_obj, sampler_node, sphere
from ..xmlnodes import Node, obj_, p_color, write_xml


FURNACE_RHO, FURNACE_LE = 0.5, 1.0
FURNACE_CAM = dict(origin=(0.1, -0.2, 0.3), target=(0.6, 0.1, -1.0), up=(0, 1, 0), fov=70, width=64, height=64)
ENV_CAM = dict(origin=(0, 0, 4), target=(0, 0, 0), up=(0, 1, 0), fov=40, width=64, height=64)
ENV_RHO = 0.8


def build_furnace(out):
    d = out / "furnace"
    write_obj(d / "meshes" / "cube_inward.obj", *box((0, 0, 0), (1, 1, 1), 0.0, inward=True))
    rho, le = FURNACE_RHO, FURNACE_LE
    path_val = le / (1 - rho)
    direct_val = le * (1 + rho)
    for integ in ("path_mis", "path_ems", "path_mats", "direct_mis", "direct_ems", "direct_mats"):
        val = path_val if integ.startswith("path") else direct_val
        spp = 64
        desc = ["Furnace test, integrator '%s'.  The camera is inside a closed cube [-1,1]^3 whose six" % integ,
                "walls (one OBJ, normals pointing INTO the cube) are diffuse with albedo rho = %g and" % rho,
                "emit area radiance Le = %g.  Analytic answer, identical in every pixel:" % le,
                "path integrators (infinite depth) converge to Le / (1 - rho) = %g;" % path_val,
                "direct integrators give Le (1 + rho) = %g.  This file: expect %g (grey, uniform)." % (direct_val, val),
                "64 x 64, fov 70, box filter.", "",
                "Correct image: uniform grey of value %g in every pixel.  Any structure (edges, corners," % val,
                "gradients) is a bug."]
        children = [integrator_node(integ), sampler_node(spp), camera_node(FURNACE_CAM, rfilter="box"),
                    mesh_obj("meshes/cube_inward.obj", diffuse(rho), area(le))]
        write_xml(d / ("furnace_%s.xml" % integ), desc, Node("scene", (), children))
    for integ in ("path_mis", "direct_mis"):
        desc = ["Environment furnace test, integrator '%s'.  An analytic diffuse sphere (albedo %g, radius 1)" % (integ, ENV_RHO),
                "under a constant environment (extension) of radiance 1.  A convex object sees the whole",
                "environment over every hemisphere and never itself, so direct and path integrators",
                "both converge to exactly %g on the sphere and 1 on the background.  64 x 64, fov 40, box filter." % ENV_RHO,
                "", "Correct image: a flat disc of value %g on a uniform background of 1 (no limb darkening," % ENV_RHO,
                "no shading at all)."]
        children = [integrator_node(integ), sampler_node(64), camera_node(ENV_CAM, rfilter="box"),
                    sphere((0, 0, 0), 1.0, diffuse(ENV_RHO)),
                    obj_("emitter", "constant", p_color("radiance", 1.0))]
        write_xml(d / ("furnace_env_%s.xml" % integ), desc, Node("scene", (), children))


def check(out):
    """The camera is inside the cube, whose normals point inward."""
    assert np.all(np.abs(FURNACE_CAM["origin"]) < 1)
    V, N, F = read_obj(out / "furnace" / "meshes" / "cube_inward.obj")
    assert np.all(np.einsum("ij,ij->i", N, -V) > 0)
