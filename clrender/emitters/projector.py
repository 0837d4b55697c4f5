"""Mitsuba 3's projection light: a pinhole at the origin of `to_world` that projects the `irradiance` texture along
its local +z, the reciprocal of the `perspective` sensor (the same fov parameters and pixel-to-direction mapping).

```xml
<emitter type="projector">
    <rgb name="irradiance" value="1"/>          <!-- irradiance on the image plane at z = 1; default 1 -->
    <!-- or <texture type="bitmap" name="irradiance"> ... </texture>: its resolution gives the aspect ratio -->
    <float name="scale" value="1"/>             <!-- a factor on the irradiance, default 1 -->
    <float name="fov" value="45"/>              <!-- degrees; or focal_length (default "50mm") -->
    <string name="fov_axis" value="x"/>         <!-- x (default), y, diagonal, smaller, larger -->
    <transform name="to_world">                 <!-- default identity: at the origin shining along +z -->
        <lookat origin="1, 1, 1" target="1, 2, 1" up="0, 0, 1"/>
    </transform>
</emitter>
```
The conventions of Mitsuba 3.9.1's projector.cpp: the aspect ratio is the irradiance texture's width / height (1 for
anything but a bitmap, as Mitsuba's textures report a resolution of 1 x 1), the fov is the perspective sensor's
(`mitsuba_x_fov`, shared with it). A point with local coordinates (x, y, z) = to_world⁻¹ (p − origin), z > 0,
is lit through uv = (0.5 − 0.5 cot(fov_x / 2) x / z, 0.5 − 0.5 aspect cot(fov_x / 2) y / z) (camera +x on the
image's left, as the sensor), only for uv within [0, 1]²; its sample's weight (intensity over dist²) is
π · scale · E(uv) / (z² cosθ), cosθ = n · (p − origin) / dist with n = to_world's image of +z, unnormalised, as
Mitsuba computes it. For a rigid to_world, z = dist cosθ makes the intensity π · scale · E / cos³θ, the inverse of
a perspective camera's importance: a plane at z = 1 facing the light receives the irradiance π · scale · E
everywhere on the projected rectangle (a diffuse plane of albedo ρ there shows ρ · scale · E), not less towards
the corners.

Emitter row (kernels/emitters/projector.h): p.projector: irradiance.xyz = E (the constant) and irradiance_tex =
NONE or the texture's row, irradiance.w = π · scale; position.xyz = the pinhole, position.w = 0.5 cot(fov_x / 2);
inv[0..2].xyz = the rows of the inverse of to_world's linear part, (inv[0].w, inv[1].w, inv[2].w) = n;
v_scale = 0.5 aspect cot(fov_x / 2).
"""
import numpy as np

from ..cameras.perspective import mitsuba_x_fov
from ..errors import SceneError
from ..scene.registry import register
from ..textures.texture import param
from .emitter import Emitter, color_or_texture, luminance


@register("emitter", "projector", fmt="mitsuba")
class ProjectorEmitter(Emitter):
    kernel = "emitters/projector.h"
    # the float4s first: a uint between them would pad the row past its 96 bytes
    PARAMS = [("position", "float4"), ("inv", "float4", 3), ("irradiance", "texture"), ("v_scale", "float")]
    FLAGS = ("DELTA",)
    METHODS = ("sample",)
    children = ("texture",)

    def __init__(self, props, children, spec):
        self.irradiance, self.texture = color_or_texture(props, children, "irradiance",
                                                         '<emitter type="projector">')
        self.scale = float(props.get_float("scale", 1.0))
        if not (self.scale >= 0 and np.isfinite(self.scale)):
            raise SceneError(f"scale must be non-negative and finite, got {self.scale:g}", props.location("scale"))
        w, h = self.texture.resolution() if self.texture is not None else (1, 1)
        self.aspect = w / h
        self.fov = mitsuba_x_fov(props, self.aspect)
        t = props.get_transform("to_world")
        m = t.matrix
        if not np.all(np.isfinite(m)) or np.any(m[3] != [0, 0, 0, 1]):
            raise SceneError(f"to_world must be finite and affine (last matrix row 0 0 0 1), got {m[3].tolist()}",
                             props.location("to_world"))
        if not abs(np.linalg.det(m[:3, :3])) > 1e-12:
            raise SceneError("to_world must be invertible", props.location("to_world"))
        self.position = m[:3, 3].copy()
        self.inverse_linear = np.linalg.inv(m[:3, :3])
        self.normal = m[:3, 2].copy()          # Mitsuba's to_world * (0, 0, 1), not normalised
        self.u_scale = 0.5 / np.tan(np.radians(self.fov) / 2)
        self.v_scale = self.u_scale * self.aspect

    def local(self, p) -> np.ndarray:
        """Local coordinates of world points (..., 3)."""
        return (np.asarray(p, np.float64) - self.position) @ self.inverse_linear.T

    def uv(self, p) -> np.ndarray:
        """The texture coordinates through which world points (..., 3) are lit (host reference for tests)."""
        q = self.local(p)
        return np.stack([0.5 - self.u_scale * q[..., 0] / q[..., 2], 0.5 - self.v_scale * q[..., 1] / q[..., 2]],
                        axis=-1)

    def lit(self, p) -> np.ndarray:
        """Whether world points (...) lie in the projected frustum (Mitsuba's test: uv in [0, 1]², z > 0)."""
        uv = self.uv(p)
        return np.all((uv >= 0) & (uv <= 1), axis=-1) & (self.local(p)[..., 2] > 0)

    def weight(self, p) -> np.ndarray:
        """The sample's weight at world points (..., 3): what a delta light's sample returns (host reference)."""
        p = np.asarray(p, np.float64)
        d = p - self.position
        z = self.local(p)[..., 2]
        cos = (d @ self.normal) / np.linalg.norm(d, axis=-1)
        e = self.texture.eval(self.uv(p)) if self.texture is not None else np.broadcast_to(self.irradiance, p.shape)
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.pi * self.scale * e / (z * z * cos)[..., None]
        return np.where((self.lit(p) & (cos > 0))[..., None], w, 0.0)

    def selection_power(self, radius, area):
        # Mitsuba's sample_ray: the flux is pi * scale * E over the image rectangle at z = 1, whose area is
        # (1 / u_scale) (1 / v_scale); a texture counts with its largest value (an upper bound)
        e = self.texture.max_value() if self.texture is not None else luminance(self.irradiance)
        return np.pi * self.scale * e / (self.u_scale * self.v_scale)

    def fill(self, p, row, ctx, shape):
        param(p, "irradiance", self.irradiance, self.texture, ctx.textures)
        p["irradiance"][3] = np.pi * self.scale
        p["position"] = (*self.position, self.u_scale)
        for k in range(3):
            p["inv"][k] = (*self.inverse_linear[k], self.normal[k])
        p["v_scale"] = self.v_scale
