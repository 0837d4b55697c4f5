"""Mitsuba 3's `constvolume`: the same value everywhere.

```xml
<medium type="heterogeneous">
    <volume type="constvolume" name="albedo">
        <rgb name="value" value="0.9, 0.8, 0.8"/>   <!-- a <float> or a colour; default 1 -->
        <transform name="to_world"> ... </transform> <!-- default identity: the box is the unit cube [0, 1]^3 -->
    </volume>
</medium>
```
A `<float>` or `<rgb>` sigma_t or albedo of a heterogeneous medium is a constvolume with the identity to_world, as
in Mitsuba 3.9.1 (Properties::get_volume). The value is read unbounded (a sigma_t may exceed 1). Its box matters
only as a medium's sigma_t: as in Mitsuba, the medium then has extinction only inside to_world's image of the unit
cube. Kernel: kernels/volumes/constvolume.h.
"""
from __future__ import annotations

import numpy as np

from ..errors import SceneError
from ..scene.registry import register
from .volume import Volume


@register("volume", "constvolume", fmt="mitsuba")
class ConstVolume(Volume):
    kernel = "volumes/constvolume.h"
    PARAMS = [("value", "float4")]

    def __init__(self, props, children, spec):
        self._read_to_world(props, spec)
        tag = props.tag("value") if props.has("value") else "float"
        self.value = np.asarray(props.get_color("value", np.ones(3), unbounded=True), np.float64)
        self.channels = 1 if tag == "float" else 3
        if not np.all(np.isfinite(self.value)):
            raise SceneError(f"value must be finite, got {self.value.tolist()}", props.location("value"))

    @classmethod
    def of(cls, value, channels: int) -> "ConstVolume":
        """A constvolume of `value` (a float or a colour) with the identity to_world: what a medium's <float> or
        <rgb> parameter stands for."""
        obj = cls.__new__(cls)
        obj.to_world = np.eye(4)
        obj.value = np.broadcast_to(np.asarray(value, np.float64), 3).copy()
        obj.channels = channels
        return obj

    def max_value(self) -> float:
        return float(self.value.max())

    def min_value(self) -> float:
        return float(self.value.min())

    def eval(self, points) -> np.ndarray:
        points = np.asarray(points, np.float64)
        return np.broadcast_to(self.value, points.shape[:-1] + (3,)).copy()

    def fill(self, row, ctx) -> None:
        row["constvolume"]["value"][:3] = self.value
