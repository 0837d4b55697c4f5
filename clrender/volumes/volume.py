"""What every volume plugin shares: Mitsuba 3's `to_world` (the map from the volume's unit cube [0, 1]^3 to the
world), the world-space bounding box of that cube's image (Mitsuba's Volume::bbox: a heterogeneous medium has
extinction only inside its sigma_t volume's box), the largest value (a heterogeneous medium's majorant), and its
row of the scene's `volumes` table (layout.ROWS "Volume"), packed once however many media read it.

A volume is the sigma_t or albedo of a `<medium type="heterogeneous">` (clrender/media/heterogeneous.py), or the albedo
of a homogeneous one. The kernel
half is `kernels/volumes/<name>.h`: `<name>_eval`, the value at a world-space point (kind VOLUME in
clrender/device/dispatch.py).
"""
from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np

from ..device import dispatch, layout
from ..errors import SceneError


class Volume(ABC):
    kernel: str = ""
    PARAMS: list = []
    FLAGS: tuple = ()
    children = ()
    #: 1 (a float: the same value in every channel) or 3 (a colour)
    channels: int = 1

    def _read_to_world(self, props, spec) -> None:
        m = np.asarray(props.get_transform("to_world").matrix, np.float64)
        if not (np.allclose(m[3], (0, 0, 0, 1)) and abs(np.linalg.det(m[:3, :3])) > 1e-30):
            raise SceneError("to_world must be an invertible affine transform (the volume's unit cube to the world)",
                             props.location("to_world") if props.has("to_world") else spec.location)
        self.to_world = m

    @property
    def to_local(self) -> np.ndarray:
        return np.linalg.inv(self.to_world)

    def bbox(self) -> tuple[np.ndarray, np.ndarray]:
        """(min, max) of the world-space box around the image of the unit cube."""
        corners = np.array([[x, y, z, 1.0] for x in (0, 1) for y in (0, 1) for z in (0, 1)])
        w = corners @ self.to_world.T
        return w[:, :3].min(axis=0), w[:, :3].max(axis=0)

    @abstractmethod
    def max_value(self) -> float:
        """The largest value over every channel (Mitsuba's Volume::max)."""

    @abstractmethod
    def min_value(self) -> float:
        """The smallest value over every channel."""

    @abstractmethod
    def eval(self, points) -> np.ndarray:
        """The value (..., 3) at world-space points (..., 3), as the kernel computes it (host reference)."""

    def pack(self, ctx) -> int:
        """This volume's row of the `volumes` table (added on the first call, the same row after)."""
        rows = ctx.volumes
        if id(self) not in rows:
            row = layout.zeros("Volume")[0]
            row["type"] = dispatch.tag_of(type(self))
            lo, hi = self.bbox()
            row["bbox_min"][:3] = lo
            row["bbox_max"][:3] = hi
            self.fill(row, ctx)
            rows[id(self)] = ctx.add_table("volumes", "Volume", row)
            ctx.volume_tags.add(int(row["type"]))
        return rows[id(self)]

    def fill(self, row, ctx) -> None:
        """Set this plugin's member of the row's union (and add its data to ctx's tables)."""
