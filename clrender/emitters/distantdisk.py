"""Distant disk (Nori's 2015 course): an infinitely far disk of uniform radiance, seen as a cone of
half-angle `thetaA` about an axis. With thetaA = 180 it is a uniform environment.

```xml
<emitter type="distantdisk">
    <color name="radiance" value="50, 50, 50"/>   <!-- required (a single number is grey) -->
    <float name="thetaA" value="6"/>              <!-- required: cone half-angle in degrees, in (0, 180] -->
    <transform name="toWorld">                    <!-- default: identity; rotation only -->
        <rotate axis="-0.8575, -0.5145, 0" angle="60.245"/>
    </transform>
</emitter>
```
The cone is about local +z, and toWorld turns local +z toward the light: directions inside the cone are
directions from the scene TO the light (with the identity, the sun is straight up the +z axis). Only the
rotation of toWorld is used (translation is ignored; a scale is removed by orthonormalising).

Emitter row (kernels/emitters/distantdisk.h): p.distantdisk: radiance.xyz; frame[0..2].xyz = world images of
local x, y, z; cos_max = cos θA, one_minus_cos = 1 − cos θA, pdf = 1 / (2π (1 − cos θA)).
"""
import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .emitter import Emitter, luminance, nonnegative_color


@register("emitter", "distantdisk")
class DistantDiskEmitter(Emitter):
    kernel = "emitters/distantdisk.h"
    PARAMS = [("radiance", "float4"), ("frame", "float4", 3), ("cos_max", "float"), ("one_minus_cos", "float"),
              ("pdf", "float")]
    FLAGS = ("INFINITE",)

    def __init__(self, props, children, spec):
        self.radiance = nonnegative_color(props, "radiance")
        self.theta_a = float(props.get_float("thetaA"))
        if not (0.0 < self.theta_a <= 180.0):
            raise SceneError(f"thetaA must be in (0, 180] degrees, got {self.theta_a:g}", props.location("thetaA"))
        m = props.get_transform("toWorld").matrix[:3, :3]
        z = m @ np.array([0.0, 0.0, 1.0])
        x = m @ np.array([1.0, 0.0, 0.0])
        nz = np.linalg.norm(z)
        if not (np.isfinite(nz) and nz > 0):
            raise SceneError("toWorld maps the cone axis (+z) to zero", props.location("toWorld"))
        z = z / nz
        x = x - z * (x @ z)
        nx = np.linalg.norm(x)
        if not nx > 1e-9:
            raise SceneError("toWorld is not a rotation (local x and z map to parallel vectors)",
                             props.location("toWorld"))
        x = x / nx
        self.frame = np.stack([x, np.cross(z, x), z])   # rows: world x, y, z axes of the cone frame

    @classmethod
    def from_axis(cls, radiance, axis, theta_a: float) -> "DistantDiskEmitter":
        """A disk made by code rather than read from a file (the sunsky's sun): `axis` toward the light (world),
        half-angle `theta_a` in degrees."""
        em = cls.__new__(cls)
        em.radiance = np.asarray(radiance, np.float64)
        em.theta_a = float(theta_a)
        z = np.asarray(axis, np.float64) / np.linalg.norm(axis)
        x = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        x = x - z * (x @ z)
        x /= np.linalg.norm(x)
        em.frame = np.stack([x, np.cross(z, x), z])
        return em

    @property
    def axis(self) -> np.ndarray:
        """Unit direction from the scene toward the light (the cone's axis)."""
        return self.frame[2]

    def selection_power(self, radius, area):
        solid_angle = 4.0 * np.pi * np.sin(np.radians(self.theta_a) / 2.0) ** 2
        return np.pi * radius ** 2 * solid_angle * luminance(self.radiance)

    def fill(self, p, row, ctx, shape):
        t = np.radians(self.theta_a)
        cos_a = np.cos(t)
        one_minus_cos = 2.0 * np.sin(t / 2.0) ** 2   # no cancellation for small cones
        p["radiance"][:3] = self.radiance
        for k in range(3):
            p["frame"][k][:3] = self.frame[k]
        with np.errstate(over="ignore"):  # a cone of thetaA 1e-30: pdf inf in float32, which the kernel handles
            p["cos_max"], p["one_minus_cos"], p["pdf"] = cos_a, one_minus_cos, 1.0 / (2.0 * np.pi * one_minus_cos)
