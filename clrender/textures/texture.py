"""What the texture plugins share: one row of the textures table.

A texture plugin declares its kernel half (`kernel`: <prefix>_eval(t, uv) in kernels/textures/<prefix>.h, reached
through the generated texture_eval) and its parameters (`PARAMS`, written by `fill`); `max_value()` and a host
`eval(uv)` serve validation and tests. A BSDF parameter declared as ("name", "texture") holds a constant colour
and the index of a texture row (NONE: the constant), which `param` fills. A float parameter (a roughness, a blend
weight, an opacity) reads the first channel of `float_view()`, the texture as Mitsuba's float lookup (`eval_1`) sees
it.
"""
from __future__ import annotations

import abc

import numpy as np

from ..device import dispatch, layout
from ..errors import SceneError


class Texture(abc.ABC):
    kernel: str = ""
    PARAMS: list = []

    def pack(self) -> np.void:
        row = layout.zeros("Texture")[0]
        row["type"] = dispatch.tag_of(type(self))
        if self.PARAMS:
            self.fill(row[dispatch.member_of(type(self))])
        return row

    def fill(self, p) -> None:
        """Write the declared parameters into `p` (this texture's member of the row's union)."""

    def texels(self) -> np.ndarray | None:
        """Pixels (N, 4) float32 stored right after the texture's row (TextureTable.add), or None."""
        return None

    def float_view(self) -> "Texture":
        """The texture whose every channel is the float that Mitsuba's `eval_1` reads where a float parameter takes
        this texture (one object per texture, so the textures table holds it once)."""
        view = self.__dict__.get("_float_view")
        if view is None:
            view = self.__dict__["_float_view"] = self.make_float_view()
        return view

    def make_float_view(self) -> "Texture":
        """See float_view; by default the texture itself (a float reads its first channel)."""
        return self

    def resolution(self) -> tuple[int, int]:
        """(width, height) in texels: 1 x 1 but for an image, as Mitsuba's textures report it (a projector takes its
        aspect ratio from it)."""
        return 1, 1

    @abc.abstractmethod
    def max_value(self) -> float:
        """The largest value of any channel (BSDFs that need colours within [0, 1] check it)."""

    @abc.abstractmethod
    def eval(self, uv) -> np.ndarray:
        """The colour at uv (..., 2) on the host (the reference the tests hold the kernel to)."""


class TextureTable:
    """The textures table being packed: each texture object once, in the order first met."""

    def __init__(self):
        self.rows: list = []
        self._index: dict[int, int] = {}
        self.tags: set[int] = set()     # the texture plugins' tags (texel rows hold no tag)
        # The scene's bsdf_tables rows, which travel with the textures since a BSDF packs with this table alone.
        self.bsdf_tables: list[np.ndarray] = []
        self._table_index: dict[bytes, int] = {}

    def add(self, texture) -> int:
        key = id(texture)
        if key not in self._index:
            self._index[key] = len(self.rows)
            self.rows.append(texture.pack())
            self.tags.add(int(self.rows[-1]["type"]))
            px = texture.texels()
            if px is not None:
                self.add_texels(px)
        return self._index[key]

    def add_texels(self, px) -> int:
        """Append pixels (N, 4) float32 as raw rows (a Texture row holds four float4s; the kernels read them as
        `(__global const float4*)(textures + row)`, since a texture's eval sees only this table); returns the
        first row."""
        px = np.ascontiguousarray(px, np.float32).reshape(-1, 4)
        per_row = layout.dtype("Texture").itemsize // 16
        pad = (-len(px)) % per_row
        px = np.concatenate([px, np.zeros((pad, 4), np.float32)])
        first = len(self.rows)
        self.rows.extend(np.frombuffer(px.tobytes(), layout.dtype("Texture")))
        return first

    def array(self) -> np.ndarray:
        return np.array(self.rows, layout.dtype("Texture")) if self.rows else layout.zeros("Texture")

    def add_bsdf_table(self, values) -> int:
        """A BSDF's lookup table (a BsdfTable row of the scene's bsdf_tables); returns its index. Equal tables
        (BSDFs with the same parameters) are stored once."""
        row = layout.zeros("BsdfTable")
        row["values"][0] = values
        key = row.tobytes()
        if key not in self._table_index:
            self._table_index[key] = len(self.bsdf_tables)
            self.bsdf_tables.append(row)
        return self._table_index[key]

    def bsdf_tables_array(self) -> np.ndarray:
        """The bsdf_tables added so far (one zero row if none: OpenCL has no empty buffers)."""
        return np.concatenate(self.bsdf_tables) if self.bsdf_tables else layout.zeros("BsdfTable")


def param(p, name: str, value, texture, table: TextureTable) -> bool:
    """Fill a ("name", "texture") or ("name", "float_texture") parameter (layout.TEXTURED): the constant `value` (a
    colour, a float), or `texture`'s row in `table` (for a float, its float view). Returns whether it refers to a
    texture (the BSDF then needs uv)."""
    if p.dtype[name].shape:
        p[name][:3] = value
    else:
        p[name] = value
    p[name + "_tex"] = layout.NONE if texture is None else table.add(texture)
    return texture is not None


def texture_child(children, name: str, owner: str):
    """The nested texture called `name` (None if there is none); any other nested texture is an error."""
    found = None
    for c in children:
        spec = getattr(c, "spec", None)
        cname = getattr(spec, "name", None)
        if cname != name:
            raise SceneError(f"{owner} takes a texture named '{name}', not {cname!r}",
                             getattr(spec, "location", None))
        if found is not None:
            raise SceneError(f"{owner} has two '{name}' textures", getattr(spec, "location", None))
        found = c
    return found
