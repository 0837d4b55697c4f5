"""Nori's perspective camera, in either dialect of the format (clrender/scene/dialect.py).

```xml
<camera type="perspective">
    <integer name="width" value="1280"/>      <!-- default 1280 -->
    <integer name="height" value="720"/>      <!-- default 720 -->
    <float name="fov" value="30"/>            <!-- horizontal field of view in degrees, default 30 -->
    <float name="nearClip" value="1e-4"/>     <!-- default 1e-4 -->
    <float name="farClip" value="1e4"/>       <!-- default 1e4; inf: no far clipping -->
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
import math

import numpy as np

from ..device import layout
from ..errors import SceneError
from ..filters.gaussian import GaussianFilter
from ..scene.dialect import mirrors_camera_x
from ..scene.registry import register

#: the device's far clip for inf (no far clipping)
NO_FAR_CLIP = 1e25


@register("camera", "perspective")
class PerspectiveCamera:
    children = ("rfilter",)

    def __init__(self, props, children, spec):
        self.width = props.get_int("width", 1280)
        self.height = props.get_int("height", 720)
        self.fov = props.get_float("fov", 30.0)
        self.near_clip = props.get_float("nearClip", 1e-4)
        self.far_clip = props.get_float("farClip", 1e4, no_limit=True)
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
        if np.any(m[3] != [0, 0, 0, 1]):
            # the camera row keeps the upper 3 x 4 part: a projective row would be dropped without a word
            raise SceneError(f"camera toWorld must be affine (last matrix row 0 0 0 1), got {m[3].tolist()}",
                             props.location("toWorld"))
        if np.linalg.norm(m[:3, 2]) < 1e-12:
            raise SceneError("camera toWorld maps the viewing direction (+z) to zero", props.location("toWorld"))
        self.mirror_x = mirrors_camera_x(spec.dialect) if spec is not None else True
        if len(children) > 1:
            raise SceneError("a camera takes at most one <rfilter>", children[1].spec.location)
        self.filter = children[0] if children else GaussianFilter()

    def pack(self) -> tuple[np.ndarray, np.ndarray]:
        """The Camera row and the filter's sampling table."""
        rows = layout.zeros("Camera")
        row = rows[0]   # a view: filled in place (np.array([row]) would leave the bytes no member covers undefined)
        m = self.to_world.matrix
        for i in range(4):
            row["to_world"][i, :3] = m[:3, i]
        if self.mirror_x:
            row["to_world"][0, :3] *= -1.0
        row["tan_half_fov"] = np.tan(np.radians(self.fov) / 2)
        row["inv_aspect"] = self.height / self.width
        # "no limit" on the device: beyond every distance a scene can hold (shapes stop at 1e18), and far from
        # float's overflow in tmax = far_clip / cos(angle) * scale
        row["near_clip"], row["far_clip"] = self.near_clip, min(self.far_clip, NO_FAR_CLIP)
        row["width"], row["height"] = self.width, self.height
        row["film_width"], row["film_height"] = self.width, self.height
        self.pack_film(row)
        table = self.filter.sampling_table()
        self.filter.pack(row, table)
        return rows, table

    def pack_film(self, row) -> None:
        """Crop window, border clipping and lens (Nori's camera: the whole film, no clipping, a pinhole)."""


def mitsuba_x_fov(props, aspect: float) -> float:
    """The horizontal field of view (degrees) of a Mitsuba sensor's ``fov``/``fov_axis`` or ``focal_length``
    (a 35 mm film's diagonal, 43.27 mm, behind a lens of that focal length; default 50 mm)."""
    if props.has("fov") and props.has("focal_length"):
        raise SceneError("give either 'fov' or 'focal_length', not both", props.location("focal_length"))
    if props.has("fov"):
        fov = props.get_float("fov")
        axis = props.get_string("fov_axis", "x").lower()
        where = props.location("fov")
        if axis == "smaller":
            axis = "y" if aspect > 1 else "x"
        elif axis == "larger":
            axis = "x" if aspect > 1 else "y"
    else:
        text = props.get_string("focal_length", "50mm")
        where = props.location("focal_length") if props.has("focal_length") else None
        num = text[:-2] if text.endswith("mm") else text
        try:
            f = float(num)
        except ValueError:
            f = -1.0
        if not (f > 0 and np.isfinite(f)):
            raise SceneError(f"bad focal_length '{text}'; expected a positive length in millimetres such as "
                             f"'50mm'", where)
        fov = np.degrees(2 * np.arctan(np.hypot(36.0, 24.0) / (2 * f)))
        axis = "diagonal"
    if not 0 < fov < 180:
        raise SceneError(f"fov must be in (0, 180) degrees, got {fov}", where)
    t = np.tan(np.radians(fov) / 2)
    if axis == "x":
        return float(fov)
    if axis == "y":
        return float(np.degrees(2 * np.arctan(t * aspect)))
    if axis == "diagonal":
        return float(np.degrees(2 * np.arctan(t / np.sqrt(1 + 1 / aspect ** 2))))
    raise SceneError(f"unknown fov_axis '{props.get_string('fov_axis')}'; expected x, y, diagonal, smaller or "
                     f"larger", props.location("fov_axis"))


@register("sensor", "perspective", fmt="mitsuba")
class MitsubaPerspectiveCamera(PerspectiveCamera):
    """Mitsuba 3's perspective sensor (camera +x on the image's left, as upstream Nori).

    ```xml
    <sensor type="perspective">
        <float name="fov" value="45"/>            <!-- degrees; or focal_length (default "50mm") -->
        <string name="fov_axis" value="x"/>       <!-- x (default), y, diagonal, smaller, larger -->
        <float name="near_clip" value="0.01"/>    <!-- default 0.01 -->
        <float name="far_clip" value="10000"/>    <!-- default 10000; inf: no far clipping -->
        <float name="focus_distance" value="5"/>  <!-- accepted, no effect (a pinhole), as in Mitsuba -->
        <float name="shutter_open" value="0"/>    <!-- and shutter_close: accepted, no effect (nothing moves) -->
        <float name="principal_point_offset_x" value="0"/>   <!-- default 0; and _y: perspective only -->
        <transform name="to_world"> ... </transform>
        <film type="hdrfilm"> ... </film>         <!-- default hdrfilm: 768 x 576, gaussian filter -->
        <sampler type="independent"> ... </sampler>   <!-- default independent, 4 samples per pixel -->
    </sensor>
    ```
    The film's crop window becomes the image; the projection is that of the whole film. The principal point offset
    shifts where each image position looks, by that fraction of the film's width (height), as Mitsuba adds it to
    its film sample (checked against Mitsuba 3.9.1 with and without a crop window); we add it to the crop window's
    offset. Blender's Mitsuba exporter writes it, mostly as 0.
    """
    children = ("film", "sampler", "medium")

    def __init__(self, props, children, spec):
        from ..films.hdrfilm import HdrFilm
        from ..samplers.independent import MitsubaIndependentSampler

        self.film = self.sampler = None
        self.medium = None   # the medium the camera sits in (a nested or referenced <medium>; None: vacuum)
        for c in children:
            slot = c.spec.tag
            if getattr(self, slot) is not None:
                raise SceneError(f"a sensor takes one <{slot}>; this is a second one", c.spec.location)
            setattr(self, slot, c)
        if self.film is None:
            self.film = HdrFilm.default()
        if self.sampler is None:
            self.sampler = MitsubaIndependentSampler.default()
        film = self.film
        self.near_clip = props.get_float("near_clip", 0.01)
        # inf means no far clipping here (Mitsuba 3.9.1 takes it too, but its rays then meet nothing: their maxt
        # becomes NaN)
        self.far_clip = props.get_float("far_clip", 1e4, no_limit=True)
        if not 0 < self.near_clip < self.far_clip:
            raise SceneError(f"need 0 < near_clip < far_clip, got {self.near_clip}, {self.far_clip}",
                             props.location("near_clip") if props.has("near_clip") else spec.location)
        self.to_world = props.get_transform("to_world")
        m = self.to_world.matrix
        if not np.all(np.isfinite(m)) or np.linalg.norm(m[:3, 2]) < 1e-12:
            raise SceneError("sensor to_world is not finite or maps the viewing direction (+z) to zero",
                             props.location("to_world"))
        if np.any(m[3] != [0, 0, 0, 1]):
            raise SceneError(f"sensor to_world must be affine (last matrix row 0 0 0 1), got {m[3].tolist()}",
                             props.location("to_world"))
        self.width, self.height = film.crop_width, film.crop_height
        self.filter = film.filter
        self.mirror_x = True
        self.lens_radius, self.focus_distance = 0.0, 1.0
        self.principal_point = (0.0, 0.0)
        self.ortho = False
        # Mitsuba reads focus_distance for every projective sensor (its base class), so exporters write it on
        # perspective and orthographic sensors too, where it changes nothing; thinlens reads it again below.
        props.get_float("focus_distance", self.far_clip)
        # Every Mitsuba sensor takes a shutter interval, which moves nothing in a scene without motion (ours)
        shutter = props.get_float("shutter_open", 0.0), props.get_float("shutter_close", 0.0)
        if shutter[1] < shutter[0]:
            raise SceneError(f"shutter_close ({shutter[1]:g}) is before shutter_open ({shutter[0]:g})",
                             props.location("shutter_close" if props.has("shutter_close") else "shutter_open"))
        self.read_projection(props, m)
        self.read_lens(props)

    def read_projection(self, props, m) -> None:
        """The field of view; the to_world may not scale (Mitsuba's rule for perspective sensors)."""
        self.fov = mitsuba_x_fov(props, self.film.full_width / self.film.full_height)
        # Mitsuba refuses a scaled or sheared camera (its columns must be orthonormal within 1e-3; mirrors are
        # fine); read as written it would change the field of view and the clip distances.
        gram = m[:3, :3].T @ m[:3, :3]
        if np.abs(gram - np.eye(3)).max() > 1e-3:
            raise SceneError(f"the sensor's to_world scales or shears (its axes' lengths: "
                             f"{np.sqrt(np.diag(gram)).round(4).tolist()}); a sensor's to_world may only rotate, "
                             f"mirror and translate, as in Mitsuba (write the fov instead of a scale)",
                             props.location("to_world"))

    def read_lens(self, props) -> None:
        """A pinhole with its principal point (thinlens overrides this: Mitsuba's has no principal point)."""
        self.principal_point = tuple(float(props.get_float(f"principal_point_offset_{a}", 0.0)) for a in "xy")
        if not np.all(np.isfinite(self.principal_point)):
            raise SceneError(f"principal_point_offset must be finite, got {list(self.principal_point)}",
                             props.location("principal_point_offset_x") or props.location("principal_point_offset_y"))

    def pack_film(self, row) -> None:
        f = self.film
        row["film_width"], row["film_height"] = f.full_width, f.full_height
        row["crop_x"] = f.crop_x + self.principal_point[0] * f.full_width
        row["crop_y"] = f.crop_y + self.principal_point[1] * f.full_height
        row["inv_aspect"] = f.full_height / f.full_width
        row["clip_window"] = 0 if f.sample_border else 1
        row["lens_radius"], row["focus_distance"] = self.lens_radius, self.focus_distance
        row["ortho"] = int(self.ortho)


@register("sensor", "thinlens", fmt="mitsuba")
class MitsubaThinLensCamera(MitsubaPerspectiveCamera):
    """Mitsuba 3's thin lens sensor: the perspective sensor with a circular aperture (depth of field).

    ```xml
    <sensor type="thinlens">
        <float name="aperture_radius" value="0.1"/>   <!-- required, in scene units -->
        <float name="focus_distance" value="5"/>      <!-- along the viewing axis; default far_clip -->
        ... every parameter of perspective ...
    </sensor>
    ```
    A ray leaves from a uniformly chosen point of the aperture disk towards the point where the pinhole ray
    through the same film position meets the plane in focus (kernels/camera.h, camera_ray_lens).
    """

    def read_lens(self, props) -> None:
        self.lens_radius = props.get_float("aperture_radius")
        if not props.has("focus_distance") and math.isinf(self.far_clip):
            raise SceneError("a thinlens sensor whose far_clip is inf needs a focus_distance (its default is far_clip)",
                             props.location("far_clip"))
        self.focus_distance = props.get_float("focus_distance", self.far_clip)
        if not 0 <= self.lens_radius < 1e30:
            raise SceneError(f"aperture_radius must be 0 or more, got {self.lens_radius}",
                             props.location("aperture_radius"))
        if not 0 < self.focus_distance < 1e30:
            raise SceneError(f"focus_distance must be positive, got {self.focus_distance}",
                             props.location("focus_distance"))


@register("sensor", "orthographic", fmt="mitsuba")
class MitsubaOrthographicCamera(MitsubaPerspectiveCamera):
    """Mitsuba 3's orthographic sensor: parallel rays along the camera's z axis.

    ```xml
    <sensor type="orthographic">
        <transform name="to_world">
            <scale x="2" y="2"/>                  <!-- the visible area: [-1, 1] x [-h/w, h/w], scaled -->
            <lookat origin="0, 5, 0" target="0, 0, 0" up="0, 0, 1"/>
        </transform>
        <float name="near_clip" value="0.01"/>    <!-- default 0.01: rays start on the plane z = near_clip -->
        <float name="far_clip" value="10000"/>    <!-- default 10000: and run for far_clip - near_clip -->
        <float name="focus_distance" value="5"/>  <!-- accepted, no effect, as in Mitsuba -->
        <film type="hdrfilm"> ... </film>
        <sampler type="independent"> ... </sampler>
    </sensor>
    ```
    Image position (x, y) in [0, 1]^2 of the full film looks from camera-space point (1 - 2x, (1 - 2y) h/w,
    near_clip) along +z (camera +x on the image's left, as Mitsuba's perspective sensor); the to_world may scale,
    which sets the visible area, as in Mitsuba (kernels/camera.h). Checked against Mitsuba 3.9.1 (twin
    `orthographic`).
    """

    def read_projection(self, props, m) -> None:
        self.fov = 90.0   # unused by the kernel's orthographic branch; keeps the row's other fields defined
        self.ortho = True   # (a to_world that collapses an axis is already refused as singular)

    def read_lens(self, props) -> None:
        """Parallel rays: no lens, no principal point (Mitsuba's orthographic sensor has neither)."""
