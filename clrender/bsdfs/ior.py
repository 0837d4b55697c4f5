"""Indices of refraction: Nori's intIOR/extIOR and Mitsuba 3's int_ior/ext_ior, which may also name a material.

The named values are Mitsuba 3's table (Hecht, Optics, 4th ed.: measured at ~589 nm between 0 and 20 °C); names
are matched case-insensitively, as Mitsuba does.
"""
from ..errors import SceneError

#: Mitsuba 3's named indices of refraction
NAMED_IORS = {
    "vacuum": 1.0, "helium": 1.000036, "hydrogen": 1.000132, "air": 1.000277, "carbon dioxide": 1.00045,
    "water": 1.3330, "acetone": 1.36, "ethanol": 1.361, "carbon tetrachloride": 1.461, "glycerol": 1.4729,
    "benzene": 1.501, "silicone oil": 1.52045, "bromine": 1.661,
    "water ice": 1.31, "fused quartz": 1.458, "pyrex": 1.470, "acrylic glass": 1.49, "polypropylene": 1.49,
    "bk7": 1.5046, "sodium chloride": 1.544, "amber": 1.55, "pet": 1.5750, "diamond": 2.419,
}


def lookup_ior(name: str, location=None) -> float:
    """The index of refraction Mitsuba's table gives the material `name` (any case)."""
    try:
        return NAMED_IORS[name.strip().lower()]
    except KeyError:
        raise SceneError(f"unknown index of refraction name {name!r}; known: {', '.join(NAMED_IORS)}",
                         location) from None


def read_iors(props):
    """intIOR and extIOR with Nori's defaults (BK7 glass inside, air outside)."""
    int_ior = props.get_float("intIOR", 1.5046)
    ext_ior = props.get_float("extIOR", 1.000277)
    for name, v in (("intIOR", int_ior), ("extIOR", ext_ior)):
        if not v > 0:
            raise SceneError(f"{name} must be positive, got {v}", props.location(name))
    return float(int_ior), float(ext_ior)


def read_ior(props, name: str, default: str | float) -> float:
    """A Mitsuba index of refraction: a <float> or a <string> naming a material of NAMED_IORS."""
    if props.has(name) and props.tag(name) == "string":
        v = lookup_ior(props.get_string(name), props.location(name))
    elif props.has(name):
        v = props.get_float(name)
    else:
        v = lookup_ior(default) if isinstance(default, str) else float(default)
    if not v > 0:
        raise SceneError(f"{name} must be positive, got {v}", props.location(name))
    return float(v)


def read_mitsuba_iors(props, int_default="bk7", ext_default="air"):
    """Mitsuba's int_ior and ext_ior (numbers or names), by default BK7 glass inside and air outside."""
    return read_ior(props, "int_ior", int_default), read_ior(props, "ext_ior", ext_default)
