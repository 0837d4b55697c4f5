from ..errors import SceneError


#: Narrower filters evaluate to zero in the kernel's single precision: the image came out black (tent, mitchell at
#: a radius of 1e-30). 1e-4 pixels still renders as a point sample.
MIN_RADIUS = 1e-4
MAX_RADIUS = 1e3


def positive_radius(props, default):
    r = props.get_float("radius", default)
    if not (MIN_RADIUS <= r < MAX_RADIUS):
        raise SceneError(f"filter radius must be at least {MIN_RADIUS:g} and below {MAX_RADIUS:g} pixels, got {r}",
                         props.location("radius"))
    return float(r)
