from ..errors import SceneError


def read_iors(props):
    """intIOR and extIOR with Nori's defaults (BK7 glass inside, air outside)."""
    int_ior = props.get_float("intIOR", 1.5046)
    ext_ior = props.get_float("extIOR", 1.000277)
    for name, v in (("intIOR", int_ior), ("extIOR", ext_ior)):
        if not v > 0:
            raise SceneError(f"{name} must be positive, got {v}", props.location(name))
    return float(int_ior), float(ext_ior)
