"""ETH Nori's uvtexture: a colour made from the surface uv itself, for checking uv parametrisations by eye.

```xml
<bsdf type="diffuse">
    <texture type="uvtexture" name="albedo"/>   <!-- no parameters -->
</bsdf>
```
The colour at uv is (|u mod 1| · (1 − 0.2 sin 16πu sin 16πv), |v mod 1| · (1 − 0.2 cos 16πu sin 16πv), 0.5):
u in red and v in green (the fractional part, sign dropped as C's fmod does), rippled by ±20 % with period
1/8 in u and v, blue fixed at 0.5 (kernels/bsdfs/texture.h).

How we know: the ETH course sources (pa1) define it so, and the course's own references agree with nothing
simpler. Its pa1 `material` test (`scenes/pa1/test-material.xml`, public in course repositories) looks
straight down at the centre of the course's `disk.obj` (unit disk in the xz plane; uv = (0.5 + 0.15625 x,
0.84375 − 0.15625 z) on the rim, (0.5, 0.8375) at the centre vertex) from (0, 3, 0), fov 1°, 1 × 1 pixel; the
`material` integrator returns albedo/π there. Averaging the luminance over the pixel footprint (4·10⁶ points,
fan-triangle uv interpolation) gives 0.271853 with the rule above against the reference 0.2718496, while
(u, v, 0) gives 0.22453 and (|u mod 1|, |v mod 1|, 0.5) without the ripple 0.23601. The pa1 sphere test
(`test-sphere.xml`) sends every ray exactly through the pole of a unit sphere (its lookat's up is parallel to
the view direction, so the camera frame collapses as Eigen's normalized() leaves it); uv = (0, 0) there gives
0.5 · 0.072169/π = 0.011486, the reference, and confirms the blue channel (u = 0.5 at the pole would give 0.04533).
Texture row (kernels/textures/uvtexture.h): no parameters.
"""
import numpy as np

from ..scene.registry import register
from .texture import Texture

RIPPLE = 0.2       # relative amplitude of the ripple
FREQUENCY = 16.0   # the ripple is sin/cos(FREQUENCY · π · u): period 1/8 in uv


@register("texture", "uvtexture")
class UvTexture(Texture):
    kernel = "textures/uvtexture.h"

    def __init__(self, props, children, spec):
        pass

    def max_value(self) -> float:
        return 1.0 + RIPPLE

    def eval(self, uv) -> np.ndarray:
        """The colour at uv (..., 2) on the host (a reference for tests)."""
        uv = np.asarray(uv, np.float64)
        u, v = uv[..., 0], uv[..., 1]
        su, cu, sv = np.sin(FREQUENCY * np.pi * u), np.cos(FREQUENCY * np.pi * u), np.sin(FREQUENCY * np.pi * v)
        r = np.abs(np.fmod(u, 1.0)) * (1.0 - RIPPLE * su * sv)
        g = np.abs(np.fmod(v, 1.0)) * (1.0 - RIPPLE * cu * sv)
        return np.stack([r, g, np.full_like(u, 0.5)], axis=-1)
