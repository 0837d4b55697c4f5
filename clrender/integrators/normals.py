"""Shading normals as colour: |n| per component, black where the camera ray escapes.

```xml
<integrator type="normals"/>
```
"""
from ..scene.registry import register
from .integrator import Integrator


@register("integrator", "normals")
class NormalsIntegrator(Integrator):
    kernel = "normals"

    def __init__(self, props, children, spec):
        pass
