"""Perfect specular reflection: wo = (-x, -y, z) in the local frame, weight 1 (a delta BSDF).

```xml
<bsdf type="mirror"/>
```
"""
from ..device.layout import ENUMS
from ..scene.registry import register
from .bsdf import Bsdf


@register("bsdf", "mirror")
class Mirror(Bsdf):
    bsdf_type = ENUMS["BSDF_MIRROR"]
    is_delta = True

    def __init__(self, props, children, spec):
        pass
