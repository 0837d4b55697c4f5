"""What the BSDF plugins share: one row of the Bsdf table.

A plugin declares its kernel half (`kernel`, whose functions kernels/bsdf.h reaches through the generated
switch), its parameter struct (`PARAMS`), its capabilities (`FLAGS`: DELTA, DIFFUSE, GLOSSY) and the methods its
header defines (`METHODS`; `sample` is required); see clrender/device/dispatch.py. `fill(p, row)` writes its
parameters into `p` (= row[prefix], the plugin's member of the row's union).
"""
from __future__ import annotations

import numpy as np

from ..device import dispatch, layout


class Bsdf:
    kernel: str = ""
    PARAMS: list = []
    FLAGS: tuple = ()
    METHODS: tuple = ("eval", "pdf", "sample")
    children = ()

    is_delta = False

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        cls.is_delta = "DELTA" in cls.FLAGS

    def pack(self) -> np.void:
        cls = type(self)
        row = layout.zeros("Bsdf")[0]
        row["type"] = dispatch.tag_of(cls)
        row["flags"] = dispatch.flags_of(cls)
        self.fill(row[dispatch.member_of(cls)] if cls.PARAMS else None, row)
        return row

    def fill(self, p, row) -> None:
        """Write the plugin's parameters into its member `p` of the row's union (`row`: header fields)."""
