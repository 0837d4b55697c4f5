"""Perfect specular reflection: wo = (-x, -y, z) in the local frame, weight 1 (a delta BSDF).

```xml
<bsdf type="mirror"/>
```
"""
from ..scene.registry import register
from .bsdf import Bsdf


@register("bsdf", "mirror")
class Mirror(Bsdf):
    kernel = "bsdfs/mirror.h"
    FLAGS = ("DELTA",)
    METHODS = ("sample",)

    def __init__(self, props, children, spec):
        pass
