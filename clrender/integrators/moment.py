"""Mitsuba 3's `moment`: the integrator it holds renders the image, and the film's second moment becomes extra
EXR channels.

```xml
<integrator type="moment">
    <integrator type="path" name="..."/>   <!-- required; more than one: the first renders (a warning) -->
</integrator>
```
Mitsuba 3.9.1 returns the first nested integrator's radiance as the image and adds, per nested integrator, the
channels `<name>.X/Y/Z` (its samples in CIE XYZ) and `m2_<name>.X/Y/Z` (their squares), each weighed by the film's
filter as any channel is, so a pixel's m2 is sum(f X^2) / sum(f) over the samples splatted onto it; an unnamed
nested integrator is `_arg_0`.

clrender's film holds per pixel sum(w L), sum(w) and sum((w L)^2) per RGB channel, where a sample drawn by filter
importance sampling carries w = f / p (kernels/filter.h). With a `box` filter every w is 1, so sum((w L)^2) / sum(w)
is sum(L^2) / N: Mitsuba's m2 estimator, of the RGB channels instead of X, Y, Z (the squares of X = a.RGB need the
cross products R G, G B, R B, which the film does not hold; for a grey image m2_Y is the same number as each of
ours). The EXR then gets `m2_<name>.R/G/B` beside R, G, B (the first moment, in RGB). With another filter w is not
1 (f / p, a constant only up to the table's steps, and of both signs for mitchell, catmullrom, lanczos), so
sum((w L)^2) / sum(w) is not Mitsuba's sum(f L^2) / sum(f): the image is rendered and the second moment left out,
with a warning. Mitsuba's own scenes that use `moment` (its test-suite's) all have box filters.
"""
import logging

from ..errors import SceneError
from ..scene.registry import register

log = logging.getLogger("clrender")


@register("integrator", "moment", fmt="mitsuba")
class Moment:
    """Not a device integrator: the scene renders ``nested`` and names the second-moment channels ``name``."""

    children = ("integrator",)

    def __init__(self, props, children, spec):
        where = '<integrator type="moment">'
        if not children:
            raise SceneError(f"{where} needs a nested <integrator> (e.g. <integrator type=\"path\"/>): the one "
                             "whose first and second moments it records", spec.location)
        for c in children:
            if isinstance(c, Moment):
                raise SceneError(f"{where} cannot hold another moment integrator", c.spec.location)
        self.nested = children[0]
        #: Mitsuba's name for the nested integrator's channels (an unnamed one is its first unnamed argument)
        self.name = children[0].spec.name or "_arg_0"
        if len(children) > 1:
            log.warning("%s: %s holds %d integrators: clrender renders the first (<integrator type=\"%s\">), whose "
                        "radiance is the image in Mitsuba too, and writes no channels for the others", spec.location,
                        where, len(children), children[0].spec.type)
        self.location = spec.location

    def channels(self, rfilter) -> str | None:
        """The prefix of the second-moment channels (``m2_<name>``), or None (with a warning) where the film's
        filter makes them differ from Mitsuba's."""
        from ..filters.box import BoxFilter

        if isinstance(rfilter, BoxFilter) and rfilter.radius == 0.5:
            return f"m2_{self.name}"
        kind = getattr(getattr(rfilter, "spec", None), "type", None)
        what = f'<rfilter type="{kind}">' if kind else "the default gaussian"
        log.warning("%s: <integrator type=\"moment\">: the film's filter is %s, so only the first moment (the image) "
                    "is written: the film's sum of squared weighted samples equals Mitsuba's second moment only with "
                    "a box filter", self.location, what)
        return None
