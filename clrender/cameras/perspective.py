"""Nori's perspective camera, in either dialect of the format (clrender/scene/dialect.py).

```xml
<camera type="perspective">
    <integer name="width" value="1280"/>      <!-- default 1280 -->
    <integer name="height" value="720"/>      <!-- default 720 -->
    <float name="fov" value="30"/>            <!-- horizontal field of view in degrees, default 30 -->
    <float name="nearClip" value="1e-4"/>     <!-- default 1e-4 -->
    <float name="farClip" value="1e4"/>       <!-- default 1e4 -->
    <transform name="toWorld">                <!-- default identity: at the origin looking down +z -->
        <lookat origin="0,0,-5" target="0,0,0" up="0,1,0"/>
    </transform>
    <rfilter type="gaussian"/>                <!-- default gaussian, radius 2, stddev 0.5 -->
</camera>
```
A film position (sx, sy) in [0,1]² (top-left origin) maps to camera space through the inverse of
S·T·P, P Nori's perspective projection (cot of half the horizontal fov, near and far clip):
- upstream dialect: S = diag(-0.5, -0.5·aspect, 1), T = translate(-1, -1/aspect, 0): camera +x appears on
  the image's **left** (as in Mitsuba), so a plain `lookat` (whose x column is "left") is unmirrored;
- eth dialect: S = diag(0.5, -0.5·aspect, 1), T = translate(1, -1/aspect, 0): camera +x on the **right**;
  those scenes put `<scale value="-1,1,1"/>` before `<lookat>`.
Both are the same camera up to the sign of camera x, so the row packs toWorld's x column negated for
upstream and the kernel (kernels/camera.h) computes the eth form. A `lookat` whose `up` is parallel to
the viewing direction leaves toWorld with zero x and y columns; as in Nori, every ray then leaves along
the viewing direction.
"""
import numpy as np

from ..device import layout
from ..errors import SceneError
from ..filters.gaussian import GaussianFilter
from ..scene.dialect import mirrors_camera_x
from ..scene.registry import register


@register("camera", "perspective")
class PerspectiveCamera:
    children = ("rfilter",)

    def __init__(self, props, children, spec):
        self.width = props.get_int("width", 1280)
        self.height = props.get_int("height", 720)
        self.fov = props.get_float("fov", 30.0)
        self.near_clip = props.get_float("nearClip", 1e-4)
        self.far_clip = props.get_float("farClip", 1e4)
        self.to_world = props.get_transform("toWorld")
        for name, v in (("width", self.width), ("height", self.height)):
            if not 0 < v <= 65536:
                raise SceneError(f"{name} must be between 1 and 65536, got {v}", props.location(name))
        if not 0 < self.fov < 180:
            raise SceneError(f"fov must be in (0, 180) degrees, got {self.fov}", props.location("fov"))
        if not 0 <= self.near_clip < self.far_clip:
            raise SceneError(f"need 0 <= nearClip < farClip, got {self.near_clip}, {self.far_clip}",
                             props.location("nearClip"))
        m = self.to_world.matrix
        if not np.all(np.isfinite(m)):
            raise SceneError("camera toWorld has NaN or infinite entries", props.location("toWorld"))
        if np.linalg.norm(m[:3, 2]) < 1e-12:
            raise SceneError("camera toWorld maps the viewing direction (+z) to zero", props.location("toWorld"))
        self.mirror_x = mirrors_camera_x(spec.dialect) if spec is not None else True
        if len(children) > 1:
            raise SceneError("a camera takes at most one <rfilter>", children[1].spec.location)
        self.filter = children[0] if children else GaussianFilter()

    def pack(self) -> tuple[np.ndarray, np.ndarray]:
        """The Camera row and the filter's sampling table."""
        row = layout.zeros("Camera")[0]
        m = self.to_world.matrix
        for i in range(4):
            row["to_world"][i, :3] = m[:3, i]
        if self.mirror_x:
            row["to_world"][0, :3] *= -1.0
        row["tan_half_fov"] = np.tan(np.radians(self.fov) / 2)
        row["inv_aspect"] = self.height / self.width
        row["near_clip"], row["far_clip"] = self.near_clip, self.far_clip
        row["width"], row["height"] = self.width, self.height
        f = self.filter
        table = f.sampling_table()
        row["filter_type"] = f.filter_type
        row["filter_bins"] = len(table) - 1
        row["filter_radius"] = f.radius
        row["filter_p0"], row["filter_p1"], row["filter_p2"] = f.p0, f.p1, f.p2
        return np.array([row]), table
