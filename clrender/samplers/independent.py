"""Independent uniform samples from a counter-based generator (Philox4x32, keyed by seed and pixel).

```xml
<sampler type="independent">
    <integer name="sampleCount" value="1"/>   <!-- samples per pixel, default 1 -->
</sampler>
```
"""
from ..errors import SceneError
from ..scene.registry import register


@register("sampler", "independent")
class IndependentSampler:
    def __init__(self, props, children, spec):
        self.sample_count = props.get_int("sampleCount", 1)
        if not 1 <= self.sample_count < 2**32:  # sample numbers are 32-bit on the device
            raise SceneError(f"sampleCount must be between 1 and {2**32 - 1}, got {self.sample_count}",
                             props.location("sampleCount"))
