"""Mitsuba 3's high dynamic range film: the image size, an optional crop window and the reconstruction filter.

```xml
<film type="hdrfilm">
    <integer name="width" value="768"/>          <!-- default 768 -->
    <integer name="height" value="576"/>         <!-- default 576 -->
    <integer name="crop_offset_x" value="0"/>    <!-- crop window (default: the whole film) -->
    <integer name="crop_offset_y" value="0"/>
    <integer name="crop_width" value="768"/>
    <integer name="crop_height" value="576"/>
    <boolean name="sample_border" value="false"/> <!-- default false: samples only inside the window -->
    <string name="pixel_format" value="rgb"/>    <!-- rgb or rgba; file_format, component_format, banner,
                                                      compensate accepted -->
    <rfilter type="gaussian"/>                   <!-- default gaussian, stddev 0.5 -->
</film>
```
The rendered image is the crop window; the sensor projects the whole film. With ``sample_border`` false (the
default) a pixel near the window's edge averages only what lies inside the window, as Mitsuba's does; true lets
its filter reach outside (kernels/render.cl, clip_window).
"""
from __future__ import annotations

from ..errors import SceneError
from ..scene.registry import register

_FORMATS = {"file_format": ("openexr", "exr", "rgbe", "hdr", "pfm"),
            "pixel_format": ("rgb", "rgba"),
            "component_format": ("float16", "float32", "uint32")}


@register("film", "hdrfilm", fmt="mitsuba")
class HdrFilm:
    children = ("rfilter",)
    #: the output options and their allowed values (the first is the default); they change no pixel here
    FORMATS = _FORMATS

    def __init__(self, props, children, spec):
        def size(name, default, low):
            v = props.get_int(name, default)
            if not low <= v <= 65536:
                raise SceneError(f"{name} must be between {low} and 65536, got {v}", props.location(name))
            return v

        self.full_width = size("width", 768, 1)
        self.full_height = size("height", 576, 1)
        self.crop_x = size("crop_offset_x", 0, 0)
        self.crop_y = size("crop_offset_y", 0, 0)
        self.crop_width = size("crop_width", self.full_width - self.crop_x, 1)
        self.crop_height = size("crop_height", self.full_height - self.crop_y, 1)
        if self.crop_x + self.crop_width > self.full_width or self.crop_y + self.crop_height > self.full_height:
            where = next((props.location(n) for n in ("crop_width", "crop_height", "crop_offset_x", "crop_offset_y")
                          if props.has(n)), spec.location if spec is not None else None)
            raise SceneError(f"the crop window ({self.crop_x}, {self.crop_y}) + {self.crop_width} x "
                             f"{self.crop_height} does not fit the {self.full_width} x {self.full_height} film", where)
        self.sample_border = props.get_bool("sample_border", False)
        for name, allowed in self.FORMATS.items():   # how Mitsuba writes its file: no effect on the image
            v = props.get_string(name, allowed[0]).lower()
            if v not in allowed:
                raise SceneError(f"{name} '{v}' is not supported; clrender takes {', '.join(allowed)}",
                                 props.location(name))
        # Mitsuba 3.9.1's hdrfilm also takes these (a watermark switch, compensated summation): no effect here
        props.get_bool("banner", True)
        props.get_bool("compensate", False)
        if len(children) > 1:
            raise SceneError("a film takes at most one <rfilter>", children[1].spec.location)
        self.filter = children[0] if children else _default_filter()

    @classmethod
    def default(cls):
        """Mitsuba's film when a sensor has none."""
        from ..scene.properties import PropertyList

        return cls(PropertyList('<film type="hdrfilm">', fmt="mitsuba"), [], None)


def _default_filter():
    from ..filters.gaussian import MitsubaGaussianFilter

    return MitsubaGaussianFilter.default()
