"""Independent uniform samples from a counter-based generator (Philox4x32, keyed by seed and pixel); Mitsuba's
stratifying samplers use scrambled Sobol points instead (kernels/rng.h).

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
    #: what the kernels draw samples with (pack.py SceneBuffers.sampler): Philox's independent numbers
    generator = "independent"

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
    """A Mitsuba sampler that stratifies its samples: rendered with clrender's stratified sampler, scrambled Sobol
    points (kernels/rng.h, CLR_SAMPLER_SOBOL): the same converged image, with noise that falls faster than
    independent samples', as Mitsuba's stratified samplers' does (their patterns differ, so the noise differs)."""
    generator = "sobol"

    def __init__(self, props, children, spec):
        super().__init__(props, children, spec)
        log.info("%s: <sampler type=\"%s\"> renders with clrender's scrambled Sobol sampler",
                 spec.location if spec is not None else "?", spec.type if spec is not None else "?")


@register("sampler", "stratified", fmt="mitsuba")
class MitsubaStratifiedSampler(_Substitute):
    """``<sampler type="stratified">`` (sample_count, seed, jitter): scrambled Sobol samples instead."""
    EXTRA = ("jitter",)


@register("sampler", "multijitter", fmt="mitsuba")
class MitsubaMultijitterSampler(_Substitute):
    """``<sampler type="multijitter">`` (sample_count, seed, jitter): scrambled Sobol samples instead."""
    EXTRA = ("jitter",)


@register("sampler", "orthogonal", fmt="mitsuba")
class MitsubaOrthogonalSampler(_Substitute):
    """``<sampler type="orthogonal">`` (sample_count, seed, jitter, strength): scrambled Sobol samples instead."""
    EXTRA = ("jitter", "strength")


@register("sampler", "ldsampler", fmt="mitsuba")
class MitsubaLdSampler(_Substitute):
    """``<sampler type="ldsampler">`` (sample_count, seed): scrambled Sobol samples instead."""


@register("sampler", "sobol", fmt="mitsuba")
class MitsubaSobolSampler(_Substitute):
    """Mitsuba 0.6's ``<sampler type="sobol">`` (sample_count, scramble), found in old files (Mitsuba 3 has none):
    clrender's scrambled Sobol samples, keyed by the render's seed rather than ``scramble``."""
    EXTRA = ("scramble",)


@register("sampler", "halton", fmt="mitsuba")
class MitsubaHaltonSampler(_Substitute):
    """Mitsuba 0.6's ``<sampler type="halton">`` (sample_count, scramble): scrambled Sobol samples instead."""
    EXTRA = ("scramble",)


@register("sampler", "hammersley", fmt="mitsuba")
class MitsubaHammersleySampler(_Substitute):
    """Mitsuba 0.6's ``<sampler type="hammersley">`` (sample_count, scramble): scrambled Sobol samples instead."""
    EXTRA = ("scramble",)
