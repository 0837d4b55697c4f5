"""What the emitter plugins share: one row of the Emitter table.

A plugin declares its kernel half (`kernel`, reached through the switches generated into
gen/emitter_dispatch.h), its parameter struct (`PARAMS`), its capabilities (`FLAGS`: DELTA, INFINITE, SURFACE)
and the methods its header defines (`METHODS`; `sample` is required; delta lights define no pdf/eval); see
clrender/device/dispatch.py. `fill(p, row, ctx, shape)` writes its parameters into `p` (= its member of the
row's union) and, for surface emitters, the row's shape fields.
"""
from __future__ import annotations

import numpy as np

from ..device import dispatch, layout
from ..errors import SceneError
from ..textures.texture import texture_child


class Emitter:
    kernel: str = ""
    PARAMS: list = []
    FLAGS: tuple = ()
    METHODS: tuple = ("sample", "pdf", "eval")

    is_area = is_delta = is_infinite = False

    def __init_subclass__(cls, **kw):
        # The host asks the same declared flags the kernels test.
        super().__init_subclass__(**kw)
        cls.is_area = "SURFACE" in cls.FLAGS
        cls.is_delta = "DELTA" in cls.FLAGS
        cls.is_infinite = "INFINITE" in cls.FLAGS

    def pack(self, ctx, shape_index, shape, shape_row) -> np.void:
        cls = type(self)
        row = layout.zeros("Emitter")[0]
        row["type"] = dispatch.tag_of(cls)
        row["flags"] = dispatch.flags_of(cls)
        row["shape"] = shape_index
        self.fill(row[dispatch.member_of(cls)] if cls.PARAMS else None, row, ctx, shape)
        return row

    def parts(self) -> list:
        """The emitters this one packs as, one row each: itself, except for an emitter made of others (`sunsky`: a
        sky envmap and a sun disk; none when it emits nothing)."""
        return [self]

    def fill(self, p, row, ctx, shape) -> None:
        """Write the plugin's parameters into its member `p` of the row's union."""

    def selection_power(self, radius: float, area: float) -> float | None:
        """The emitted power (luminance of the flux, W) for light selection in proportion to power: `radius` is the
        scene's bounding-sphere radius (lights at infinity deliver power through its disk), `area` the emitting
        shape's area (surface emitters). None: unknown (pack_scene then gives it the mean of the others)."""
        return None


def nonnegative_color(props, name, default=None, **kw):
    """A colour property that must be >= 0 (``kw``: get_color's options, e.g. ``emitter=True`` for a Mitsuba
    emitter's spectrum)."""
    c = props.get_color(name, **kw) if default is None else props.get_color(name, default, **kw)
    c = np.asarray(c, np.float64)
    if np.any(c < 0) or not np.all(np.isfinite(c)):
        raise SceneError(f"{name} must be non-negative and finite, got {c.tolist()}", props.location(name))
    return c


def color_or_texture(props, children, name: str, owner: str):
    """A Mitsuba emitter's colour parameter that may instead be a nested texture of that name (area's `radiance`,
    projector's `irradiance`): (colour, texture). With a texture the colour is 1 and unused; else the property, default
    1 (Mitsuba's emitter spectrum convention), non-negative."""
    texture = texture_child(children, name, owner)
    if texture is None:
        return nonnegative_color(props, name, np.ones(3), emitter=True), None
    if props.has(name):
        raise SceneError(f"{name} given both as a colour and as a texture", props.location(name))
    return np.ones(3), texture


LUMINANCE = np.array([0.212671, 0.715160, 0.072169])   # linear sRGB (Rec. 709) luminance weights


def luminance(c) -> float:
    return float(np.asarray(c, np.float64) @ LUMINANCE)
