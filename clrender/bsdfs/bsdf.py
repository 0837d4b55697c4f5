"""What the BSDF plugins share: one row of the Bsdf table (kernels/bsdf.h dispatches on its type)."""
from __future__ import annotations

import numpy as np

from ..device import layout


class Bsdf:
    bsdf_type = 0
    children = ()

    def pack(self) -> np.void:
        row = layout.zeros("Bsdf")[0]
        row["type"] = self.bsdf_type
        self.fill(row)
        return row

    def fill(self, row) -> None:
        """Write the plugin's parameters into its Bsdf row."""
