"""Mitsuba 3's isotropic phase function: every direction equally likely, 1 / (4 pi); the default of a medium
without a nested phase function.

```xml
<phase type="isotropic"/>                    <!-- no parameters -->
```
Kernel: kernels/phase/isotropic.h (sampled exactly: weight 1).
"""
from ..scene.registry import register
from .phase import Phase


@register("phase", "isotropic", fmt="mitsuba")
class Isotropic(Phase):
    kernel = "phase/isotropic.h"

    def __init__(self, props=None, children=(), spec=None):
        pass
