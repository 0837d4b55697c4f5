from ..errors import SceneError


def positive_radius(props, default):
    r = props.get_float("radius", default)
    if not (r > 0 and r < 1e3):
        raise SceneError(f"filter radius must be positive, got {r}", props.location("radius"))
    return float(r)
