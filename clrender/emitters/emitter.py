"""What the emitter plugins share: one row of the Emitter table (kernels/emitter.h dispatches on its type)."""
from __future__ import annotations

import numpy as np

from ..device import layout
from ..errors import SceneError


class Emitter:
    emitter_type = 0
    is_area = False
    is_delta = False
    is_infinite = False

    def pack(self, ctx, shape_index, shape, shape_row) -> np.void:
        row = layout.zeros("Emitter")[0]
        row["type"] = self.emitter_type
        row["shape"] = shape_index
        self.fill(row, ctx, shape)
        return row

    def fill(self, row, ctx, shape) -> None:
        """Write the plugin's parameters into its Emitter row."""


def nonnegative_color(props, name, default=None):
    c = props.get_color(name) if default is None else props.get_color(name, default)
    c = np.asarray(c, np.float64)
    if np.any(c < 0) or not np.all(np.isfinite(c)):
        raise SceneError(f"{name} must be non-negative and finite, got {c.tolist()}", props.location(name))
    return c
