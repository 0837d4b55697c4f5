"""Scene objects as XML nodes: camera, sampler, integrator, BSDFs, meshes, spheres, area lights."""
from .xmlnodes import obj_, p_color, p_float, p_int, p_point, p_str, p_transform, t_lookat


def camera_node(cam, rfilter=None):
    return obj_(
        "camera", "perspective",
        p_float("fov", cam["fov"]),
        p_int("width", cam["width"]),
        p_int("height", cam["height"]),
        p_transform("toWorld", t_lookat(cam["origin"], cam["target"], cam["up"])),
        obj_("rfilter", rfilter) if rfilter else None,
    )


def sampler_node(spp):
    return obj_("sampler", "independent", p_int("sampleCount", spp))


def integrator_node(name, **kw):
    props = []
    if name == "av":
        props.append(p_float("length", kw.get("length", 1.0)))
    return obj_("integrator", name, *props)


def diffuse(albedo):
    return obj_("bsdf", "diffuse", p_color("albedo", albedo))


def microfacet(alpha, kd, int_ior=None):
    props = [p_float("alpha", alpha)]
    if int_ior is not None:
        props.append(p_float("intIOR", int_ior))
    props.append(p_color("kd", kd))
    return obj_("bsdf", "microfacet", *props)


def dielectric(int_ior=1.5, ext_ior=1.0):
    return obj_("bsdf", "dielectric", p_float("intIOR", int_ior), p_float("extIOR", ext_ior))


def mesh_obj(filename, *children, to_world=None, comment=None):
    props = [p_str("filename", filename)]
    if to_world is not None:
        props.append(to_world)
    return obj_("mesh", "obj", *props, *children, comment=comment)


def mesh_ply(filename, *children, to_world=None, comment=None):
    props = [p_str("filename", filename)]
    if to_world is not None:
        props.append(to_world)
    return obj_("mesh", "ply", *props, *children, comment=comment)


def sphere(center, radius, *children, comment=None):
    return obj_("mesh", "sphere", p_point("center", center), p_float("radius", radius), *children,
                comment=comment)


def area(radiance):
    return obj_("emitter", "area", p_color("radiance", radiance))
