"""The BSDF value at the first hit, seen from the camera, towards the shading normal: f(wi = −ray, wo = n).

```xml
<integrator type="material"/>
```
Black where the ray escapes, where it hits a surface from behind (a one-sided BSDF is 0 there) and for delta
BSDFs (their eval is 0). A test of BSDFs and textures without any light: a diffuse surface gives albedo/π.

How we know (ETH Nori's pa1 `material` integrator; its test `scenes/pa1/test-material.xml`, public in course
repositories): wo is fixed at the shading normal and wi is the direction back to the camera. The course's
unit disk (normal +y) with albedo 0.5 seen from above gives 0.5/π = 0.159155, the first reference (the disk of
albedo 1 one unit further down is hidden); the same disk rotated 180° about z (normal −y) seen from above gives
0, the second; a uvtexture on the disk gives 0.271853 against 0.2718496 (clrender/textures/uvtexture.py).
Kernel: kernels/integrators/material.h.
"""
from ..scene.registry import register
from .integrator import Integrator


@register("integrator", "material")
class MaterialIntegrator(Integrator):
    kernel = "material"

    def __init__(self, props, children, spec):
        pass
