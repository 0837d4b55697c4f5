"""What the path-tracing integrators share (path_mats.py, path_ems.py, path_mis.py): Nori's optional maxDepth, and
Russian roulette as Nori's (from depth 3, continue with probability min(max(throughput) eta², 0.99)).
The kernel is kernels/integrators/path.h, selected by <name>.h.

Mitsuba 3's `path` (MitsubaPath below) runs the same stages with Mitsuba's rules:

```xml
<integrator type="path">
    <integer name="max_depth" value="-1"/>        <!-- -1 (default): no limit; 1: emitters seen directly;
                                                        2: direct illumination; 0: nothing -->
    <integer name="rr_depth" value="5"/>          <!-- Russian roulette from this depth on (default 5) -->
    <boolean name="hide_emitters" value="false"/> <!-- camera rays see through emitters, not the environment -->
</integrator>
```
Emitter and BSDF samples are combined by the power heuristic; after each BSDF sample, once the path has rr_depth
segments, it continues with probability min(max(throughput) eta², 0.95) (Mitsuba's src/integrators/path.cpp).
hide_emitters as Mitsuba 3.9 renders it: the camera ray passes through shapes that carry an area emitter (front or
back) and sees black where it escapes; reflections still show emitters. Kernel: kernels/integrators/path_mitsuba.h.

`volpath` and `volpathmis` (same parameters) are Mitsuba's volumetric path tracers: on surfaces the same estimate as
`path`, except that null events (a null BSDF, a mask's transparent part, a thin dielectric's transmission) do not
count toward max_depth, and hide_emitters hides only the emission met before the first real bounce (the hidden
emitters' surfaces still reflect); in scenes with participating media (clrender/media/) they also sample free
flights and scatter in them (kernels/integrators/media.h; both with spectral MIS, so the same image and noise).
`path` ignores media, as Mitsuba's does. `prb` and `prbvolpath`, Mitsuba's path replay integrators, render forward
as `path` (hide_emitters refused: Mitsuba treats it differently there; prbvolpath with media refused, as path
would ignore them). Checked against Mitsuba 3.9.1 itself (twin scenes integrator_volpath*, media_*).

```xml
<integrator type="ptracer">
    <integer name="max_depth" value="-1"/>        <!-- as path's -->
    <integer name="rr_depth" value="5"/>          <!-- as path's -->
    <integer name="samples_per_pass" value="-1"/> <!-- how Mitsuba splits its work: no effect here -->
</integrator>
```
`ptracer`, Mitsuba 3's particle tracer (light paths connected to the camera at each bounce), renders as `path` with
the same `max_depth` and `rr_depth`, with a warning: both estimate the same image, except where the camera sees a surface through smooth (delta)
reflections or refractions, which a particle tracer cannot connect to the camera (Mitsuba's ptracer leaves those
black; `path` shows them). Its `hide_emitters` is refused: Mitsuba's ptracer then leaves out only the emitters'
own connections to the camera (the emitting surfaces stay opaque), where `path` lets camera rays pass through them.
"""
import logging

from ..errors import SceneError
from ..scene.registry import register
from .integrator import NO_LIMIT, Integrator

log = logging.getLogger("clrender")


#: depths are 32-bit on the device (a larger one left as an OverflowError traceback while packing)
MAX_DEPTH = 2**31 - 1


class PathIntegrator(Integrator):
    needs_emitter = True  # sees nothing but emitted light

    def __init__(self, props, children, spec):
        depth = props.get_int("maxDepth", -1)
        if depth == 0 or depth < -1 or depth > MAX_DEPTH:
            raise SceneError(f"maxDepth must be -1 (no limit) or at least 1 (and at most {MAX_DEPTH}), got {depth}",
                             props.location("maxDepth"))
        self.max_depth = NO_LIMIT if depth == -1 else depth


def mitsuba_depths(props, integrator):
    """Mitsuba's max_depth (-1 = no limit, else >= 0) and rr_depth (>= 1), checked as Mitsuba checks them."""
    depth = props.get_int("max_depth", -1)
    if depth < -1 or depth > MAX_DEPTH:
        raise SceneError(f"{integrator}: max_depth must be -1 (no limit) or at least 0 (and at most {MAX_DEPTH}), "
                         f"got {depth}",
                         props.location("max_depth"))
    rr = props.get_int("rr_depth", 5)
    if not 1 <= rr <= MAX_DEPTH:
        raise SceneError(f"{integrator}: rr_depth must be at least 1 (and at most {MAX_DEPTH}), got {rr}",
                         props.location("rr_depth"))
    return (NO_LIMIT if depth == -1 else depth), rr


@register("integrator", "path", fmt="mitsuba")
@register("integrator", "volpath", fmt="mitsuba")
@register("integrator", "volpathmis", fmt="mitsuba")
@register("integrator", "prb", fmt="mitsuba")
@register("integrator", "prbvolpath", fmt="mitsuba")
@register("integrator", "ptracer", fmt="mitsuba")
class MitsubaPath(Integrator):
    kernel = "path_mitsuba"
    PARAMS = [("hide_emitters", "uint"), ("volpath", "uint")]
    needs_emitter = True  # sees nothing but emitted light

    def __init__(self, props, children, spec):
        self.max_depth, self.rr_depth = mitsuba_depths(props, f'<integrator type="{spec.type}">')
        self.hide_emitters = props.get_bool("hide_emitters", False)
        self.volpath = spec.type in ("volpath", "volpathmis")
        if self.hide_emitters and (spec.type.startswith("prb") or spec.type == "ptracer"):
            raise SceneError(f'<integrator type="{spec.type}">: hide_emitters is not supported with {spec.type} '
                             '(Mitsuba hides emitters differently there); use path or volpath',
                             props.location("hide_emitters"))
        if spec.type == "ptracer":
            props.get_int("samples_per_pass", -1)       # how Mitsuba splits its work: no effect on the image
            log.warning("%s: <integrator type=\"ptracer\"> (Mitsuba's particle tracer) is rendered by clrender's "
                        "path tracer with the same max_depth and rr_depth: the same image, except that surfaces seen "
                        "through smooth mirrors or glass, which Mitsuba's ptracer leaves black, are shown",
                        spec.location)

    def fill(self, p):
        p["hide_emitters"] = int(self.hide_emitters)
        p["volpath"] = int(self.volpath)
