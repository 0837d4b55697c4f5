"""What the composite BSDFs (twosided, blendbsdf, mask) share: nested BSDFs packed as rows after their parent's.

A composite's row refers to each child by its offset from the composite's own row (`b + offset` in C: rows are
one array), and the generated dispatch (clrender/device/dispatch.py) calls the child through the switch one
level down: OpenCL C has neither recursion nor function pointers, so the supported depth of nesting is fixed
(dispatch.BSDF.composite_levels); deeper nesting is a located error. The composite's flags are its own plus the
union of its children's (DELTA, DIFFUSE, GLOSSY, UV, TRANSMISSION).
"""
from __future__ import annotations

from ..device import dispatch
from ..errors import SceneError
from .bsdf import Bsdf

_CHILD_FLAGS = ("DELTA", "DIFFUSE", "GLOSSY", "UV", "TRANSMISSION")


def composite_depth(bsdf) -> int:
    """0 for a leaf BSDF, 1 + the deepest child's for a composite."""
    kids = getattr(bsdf, "bsdfs", ())
    return 1 + max(composite_depth(c) for c in kids) if kids else 0


class Composite(Bsdf):
    COMPOSITE = True
    children = ("bsdf", "texture")
    owner = ""

    def read_children(self, spec, children, counts: tuple, textures: tuple = ()):
        """Split nested objects into BSDFs (`counts`: the numbers allowed) and named textures."""
        where = getattr(spec, "location", None)
        self.bsdfs = [c for c in children if isinstance(c, Bsdf)]
        self.textures = {}
        for c in children:
            if isinstance(c, Bsdf):
                continue
            spec = getattr(c, "spec", None)
            name = getattr(spec, "name", None)
            if name not in textures:
                takes = f"a texture named {' or '.join(repr(t) for t in textures)}" if textures else "no texture"
                raise SceneError(f"{self.owner} takes {takes}, not {name!r}", getattr(spec, "location", None))
            if name in self.textures:
                raise SceneError(f"{self.owner} has two '{name}' textures", getattr(spec, "location", None))
            self.textures[name] = c
        if len(self.bsdfs) not in counts:
            want = " or ".join(str(n) for n in counts)
            raise SceneError(f"{self.owner} needs {want} nested <bsdf>, got {len(self.bsdfs)}", where)
        depth = composite_depth(self)
        levels = dispatch.BSDF.composite_levels
        if depth > levels:
            raise SceneError(f"composite BSDFs (twosided, blendbsdf, mask, normalmap, bumpmap) nested {depth} deep; "
                             f"at most {levels} "
                             f"levels are supported", where)

    def read_fraction(self, props, name: str):
        """(value, texture) of a parameter in [0, 1], default 0.5: a number, or the nested texture `name` (read by
        read_children) whose values stay within [0, 1]; not both. A texture is read as Mitsuba's float lookup reads
        it (its float view), a colour as its channels' mean."""
        from .mitsuba_params import float_value

        texture = self.textures.get(name)
        if texture is not None and props.has(name):
            raise SceneError(f"{name} given both as a number and as a texture", props.location(name))
        texture = None if texture is None else texture.float_view()
        value = float_value(props, name, 0.5)
        if not 0 <= value <= 1:
            raise SceneError(f"{name} must be within [0, 1], got {value}", props.location(name))
        if texture is not None and texture.max_value() > 1:
            article = "an" if name[0] in "aeiou" else "a"
            raise SceneError(f"{article} {name} texture must stay within [0, 1]",
                             getattr(texture.spec, "location", None))
        return value, texture

    def capabilities(self) -> frozenset:
        out = set(self.own_capabilities())
        for c in self.bsdfs:
            out |= c.capabilities() & set(_CHILD_FLAGS)
        return frozenset(out)

    def pack_rows(self, textures) -> list:
        rows, offsets = [None], []
        for c in self.bsdfs:
            offsets.append(len(rows))
            rows += c.pack_rows(textures)
        self.child_offsets = offsets
        own = self.pack(textures)
        defs = dispatch.flag_defines()
        for off in offsets:
            for f in _CHILD_FLAGS:
                own["flags"] |= rows[off]["flags"] & defs[f"BSDF_{f}"]
        rows[0] = own
        return rows

    def pack(self, textures=None):
        if not hasattr(self, "child_offsets"):
            raise RuntimeError(f"{type(self).__name__}: pack the composite with pack_rows (its children follow it)")
        return super().pack(textures)
