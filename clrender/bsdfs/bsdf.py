"""What the BSDF plugins share: one row of the Bsdf table.

A plugin declares its kernel half (`kernel`, whose functions kernels/bsdf.h reaches through the generated
switch), its parameter struct (`PARAMS`), its capabilities (`FLAGS`: DELTA, DIFFUSE, GLOSSY, TRANSMISSION; a plugin
whose parameters decide one overrides `capabilities`) and the methods its header defines (`METHODS`; `sample` is
required); see clrender/device/dispatch.py. `fill(p, row, textures)` writes
its parameters into `p` (= row[prefix], the plugin's member of the row's union); a colour parameter declared
("name", "texture") is filled by clrender.textures.texture.param, which adds its texture to `textures`.
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
        # delta only when every lobe is (kernels/bsdf.h's bsdf_is_delta): a plastic has a delta and a diffuse lobe
        cls.is_delta = "DELTA" in cls.FLAGS and not {"DIFFUSE", "GLOSSY"} & set(cls.FLAGS)

    def own_capabilities(self) -> frozenset:
        """Its own capabilities (a composite's, without its children's)."""
        return frozenset(type(self).FLAGS)

    def capabilities(self) -> frozenset:
        """The flags of this BSDF's row (less UV, which packing finds): its class's FLAGS, plus what its parameters
        add (a principled BSDF transmits when spec_trans is given). Read before packing (twosided asks)."""
        return self.own_capabilities()

    def pack_rows(self, textures) -> list:
        """This BSDF's rows for the scene's Bsdf table: its own first, then (composites) its children's, which
        the first refers to by offset (see clrender/bsdfs/composite.py)."""
        return [self.pack(textures)]

    def pack(self, textures=None) -> np.void:
        """The Bsdf row; texture parameters (and lookup tables) go to `textures` (a TextureTable; by default the
        plugin's own, left in `self.textures_table` and `self.bsdf_tables` as arrays for tests that run a lone
        BSDF)."""
        from ..textures.texture import TextureTable

        cls = type(self)
        own = textures is None
        table = TextureTable() if own else textures
        row = layout.zeros("Bsdf")[0]
        row["type"] = dispatch.tag_of(cls)
        uses_uv = self.fill(row[dispatch.member_of(cls)] if cls.PARAMS else None, row, table)
        row["flags"] = dispatch.flags_of(cls, self.own_capabilities()) | \
            (dispatch.flag_defines()["BSDF_UV"] if uses_uv else 0)
        if own:
            self.textures_table = table.array()
            self.bsdf_tables = table.bsdf_tables_array()
        return row

    def fill(self, p, row, textures) -> bool:
        """Write the plugin's parameters into its member `p` of the row's union (`row`: header fields); return
        whether a parameter reads a texture over the surface (the kernels then compute uv)."""
        return False
