"""Scenes of our own for the volume tests: an orthographic camera looking straight down (-z) through an absorbing
heterogeneous medium (albedo 0) in a wide null slab at an emitter of radiance 1, so that each pixel is the
transmittance exp(-integral of sigma_t) along its vertical rays."""
from __future__ import annotations

import numpy as np

from media.media_common import HEAD, INTERIOR, box, heterogeneous_xml, integrator, ortho_sensor

SIZE = 8    # pixels along each side


def look_down(sigma_t: str, half_width: float = 0.5, centre=(0.0, 0.0), spp: int = 512, scale: float = 1.0,
              slab_half_depth: float = 1.0) -> str:
    """The scene: the camera sees the square of `half_width` about `centre` (x, y); the medium (sigma_t, an
    element) fills the slab |z| <= slab_half_depth, 40 wide; the emitter lies below it."""
    med = heterogeneous_xml(sigma_t, '<float name="albedo" value="0"/>', scale=scale, mid="m")
    cx, cy = centre
    return (f'{HEAD}{integrator("volpath")}{med}'
            f'{ortho_sensor((cx, cy, 5), (cx, cy, -10), half_width, SIZE, spp)}'
            f'{box((20, 20, slab_half_depth), inner=INTERIOR.format("m"))}'
            f'<shape type="rectangle"><transform name="to_world"><scale value="30"/><translate z="-3"/></transform>'
            f'<emitter type="area"><rgb name="radiance" value="1"/></emitter></shape></scene>')


def pixel_points(half_width: float = 0.5, centre=(0.0, 0.0), sub: int = 1) -> np.ndarray:
    """(SIZE, SIZE, sub*sub, 2) points (x, y) spread evenly over each pixel of look_down's image (row 0 at the top,
    +y; column 0 at the left, -x: Mitsuba's camera puts its local +x, world -x here, on the image's left)."""
    f = (np.arange(SIZE * sub) + 0.5) / (SIZE * sub)
    x = centre[0] - half_width + 2 * half_width * f
    y = centre[1] + half_width - 2 * half_width * f
    yy, xx = np.meshgrid(y, x, indexing="ij")
    pts = np.stack([xx, yy], -1).reshape(SIZE, sub, SIZE, sub, 2).transpose(0, 2, 1, 3, 4)
    return pts.reshape(SIZE, SIZE, sub * sub, 2)
