"""Independent uniform samples from a counter-based generator (Philox4x32, keyed by seed and pixel).

```xml
<sampler type="independent">
    <integer name="sampleCount" value="1"/>   <!-- samples per pixel, default 1 -->
</sampler>
```
"""
import logging

from ..errors import SceneError
from ..scene.registry import register

log = logging.getLogger("clrender")


@register("sampler", "independent")
class IndependentSampler:
    def __init__(self, props, children, spec):
        self.sample_count = props.get_int("sampleCount", 1)
        if not 1 <= self.sample_count < 2**32:  # sample numbers are 32-bit on the device
            raise SceneError(f"sampleCount must be between 1 and {2**32 - 1}, got {self.sample_count}",
                             props.location("sampleCount"))


@register("sampler", "independent", fmt="mitsuba")
class MitsubaIndependentSampler(IndependentSampler):
    """Mitsuba 3's independent sampler.

    ```xml
    <sampler type="independent">
        <integer name="sample_count" value="4"/>   <!-- samples per pixel, default 4 -->
        <integer name="seed" value="0"/>           <!-- accepted; clrender's seed is the render's -->
    </sampler>
    ```
    """

    #: the parameters besides sample_count and seed that a sampler type accepts (they shape its noise only)
    EXTRA: tuple = ()

    def __init__(self, props, children, spec):
        self.sample_count = props.get_int("sample_count", 4)
        if not 1 <= self.sample_count < 2**32:
            raise SceneError(f"sample_count must be between 1 and {2**32 - 1}, got {self.sample_count}",
                             props.location("sample_count"))
        props.get_int("seed", 0)
        for name in self.EXTRA:
            if props.has(name):
                props.mark_used(name)

    @classmethod
    def default(cls):
        obj = cls.__new__(cls)
        obj.sample_count = 4
        obj.spec = None
        return obj


class _Substitute(MitsubaIndependentSampler):
    """A Mitsuba sampler that changes how noise is spread, not the image it converges to: rendered with
    independent samples, with a warning."""

    def __init__(self, props, children, spec):
        super().__init__(props, children, spec)
        log.warning("%s: <sampler type=\"%s\"> renders with clrender's independent sampler (same converged "
                    "image, different noise)", spec.location if spec is not None else "?",
                    spec.type if spec is not None else "?")


@register("sampler", "stratified", fmt="mitsuba")
class MitsubaStratifiedSampler(_Substitute):
    """``<sampler type="stratified">`` (sample_count, seed, jitter): independent samples instead, a warning."""
    EXTRA = ("jitter",)


@register("sampler", "multijitter", fmt="mitsuba")
class MitsubaMultijitterSampler(_Substitute):
    """``<sampler type="multijitter">`` (sample_count, seed, jitter): independent samples instead, a warning."""
    EXTRA = ("jitter",)


@register("sampler", "orthogonal", fmt="mitsuba")
class MitsubaOrthogonalSampler(_Substitute):
    """``<sampler type="orthogonal">`` (sample_count, seed, jitter, strength): independent samples instead."""
    EXTRA = ("jitter", "strength")


@register("sampler", "ldsampler", fmt="mitsuba")
class MitsubaLdSampler(_Substitute):
    """``<sampler type="ldsampler">`` (sample_count, seed): independent samples instead, a warning."""
