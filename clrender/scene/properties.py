"""Typed, located properties of one scene object (the ``<float name=... value=.../>`` children).

Values are parsed eagerly by the XML parser, so a malformed number is reported where it is written;
the getters then check kind and component count, and remember which properties a plugin consumed so
that :meth:`PropertyList.check_unused` can flag typos like ``<float name="radus" .../>``.
"""
from __future__ import annotations

import math

from dataclasses import dataclass
from typing import Any, Iterator

import numpy as np

from ..errors import SceneError, SourceLocation
from .transform import Transform

PROPERTY_TAGS = ("boolean", "integer", "float", "string", "point", "vector", "color", "transform")
#: property tags of Mitsuba 3's format (rgb and spectrum are stored as RGB triples)
MITSUBA_PROPERTY_TAGS = ("boolean", "integer", "float", "string", "point", "vector", "rgb", "spectrum", "transform")
_ARRAY_TAGS = ("point", "vector", "color", "rgb", "spectrum")
#: what a colour parameter accepts in each format (the first names it in messages): Mitsuba takes rgb, spectrum
#: and a plain number (grey); "color" is what code (registry.instantiate) may pass
_COLOR_TAGS = {"nori": ("color",), "mitsuba": ("rgb", "spectrum", "float", "integer", "color")}


class _Required:
    """Sentinel default meaning "this property must be given"."""

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()


@dataclass
class Property:
    name: str
    tag: str
    value: Any
    location: SourceLocation | None = None
    raw: str | None = None
    used: bool = False
    #: a Mitsuba <spectrum>: (wavelengths, values), or (None, constant); its RGB depends on the use (emitter or not)
    spectrum: tuple | None = None


def _normalise(tag: str, value: Any) -> Any:
    """Coerce a programmatically supplied value to the stored representation of ``tag``."""
    if tag == "boolean":
        if not isinstance(value, (bool, np.bool_)):
            raise TypeError(f"a boolean property needs a bool, got {value!r}")
        return bool(value)
    if tag == "integer":
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            raise TypeError(f"an integer property needs an int, got {value!r}")
        return int(value)
    if tag == "float":
        return float(value)
    if tag == "string":
        return str(value)
    if tag in _ARRAY_TAGS:
        a = np.array(value, dtype=np.float64).reshape(-1)
        if a.size == 0:
            raise ValueError(f"a {tag} property needs at least one number")
        a.setflags(write=False)
        return a
    if tag == "transform":
        return value if isinstance(value, Transform) else Transform(value)
    raise ValueError(f"unknown property tag {tag!r}; expected one of "
                     f"{', '.join(dict.fromkeys(PROPERTY_TAGS + MITSUBA_PROPERTY_TAGS))}")


class PropertyList:
    """The properties of one object, in document order, keyed by name."""

    def __init__(self, owner: str = "<object>", owner_location: SourceLocation | None = None, fmt: str = "nori"):
        self.owner = owner
        self.format = fmt
        self._asked: list[str] = []   # every name a getter asked for, given or not: what the plugin takes
        self.owner_location = owner_location
        self._props: dict[str, Property] = {}

    # --- filling ----------------------------------------------------------------------------------
    def add(self, name: str, tag: str, value: Any, location: SourceLocation | None = None,
            raw: str | None = None) -> None:
        """Add a property; giving the same name twice is a :class:`SceneError` at the second one."""
        first = self._props.get(name)
        if first is not None:
            where = f" (first at line {first.location.line})" if first.location and first.location.line else ""
            raise SceneError(f"property '{name}' given twice{where}", location)
        self._props[name] = Property(name, tag, _normalise(tag, value), location, raw)

    def rename(self, old: str, new: str) -> None:
        """Give property ``old`` the name ``new``, keeping its place (an old file's upgrade renames parameters)."""
        if new in self._props:
            first = self._props[new]
            raise SceneError(f"property '{old}' becomes '{new}', which is given too (at line "
                             f"{first.location.line if first.location else '?'})", self._props[old].location)
        self._props = {(new if k == old else k): v for k, v in self._props.items()}
        self._props[new].name = new

    def remove(self, name: str) -> None:
        del self._props[name]

    # --- introspection (none of these mark a property used) ---------------------------------------
    def has(self, name: str) -> bool:
        return name in self._props

    __contains__ = has

    def __len__(self) -> int:
        return len(self._props)

    def __iter__(self) -> Iterator[str]:
        return iter(self._props)

    def names(self) -> list[str]:
        return list(self._props)

    def _entry(self, name: str) -> Property:
        try:
            return self._props[name]
        except KeyError:
            raise KeyError(f"no property {name!r} in {self.owner}") from None

    def peek(self, name: str) -> Any:
        """The stored value, without marking the property used (for tools that look
        at a scene without being its plugin: the content hash)."""
        return self._entry(name).value

    def location(self, name: str) -> SourceLocation | None:
        return self._entry(name).location

    def tag(self, name: str) -> str:
        return self._entry(name).tag

    def raw(self, name: str) -> str | None:
        """The value as written in the file (before e.g. filename resolution); None if built in code."""
        return self._entry(name).raw

    def mark_used(self, name: str) -> None:
        self._entry(name).used = True

    def unused(self) -> list[str]:
        return [p.name for p in self._props.values() if not p.used]

    def check_unused(self) -> None:
        for p in self._props.values():
            if not p.used:
                also = ""
                if self.format == "mitsuba":   # Nori's messages stay as they were
                    takes = ", ".join(n for n in self._asked if n != p.name)
                    also = f"; it takes {takes}" if takes else "; it takes no properties"
                raise SceneError(f"property '{p.name}' is not used by {self.owner}{also}", p.location)

    def __repr__(self) -> str:
        inner = ", ".join(f"{p.tag} {p.name}={p.value!r}" for p in self._props.values())
        return f"PropertyList({self.owner}: {inner})"

    # --- typed getters ----------------------------------------------------------------------------
    def _fetch(self, name: str, tags: tuple[str, ...], default: Any) -> Property | None:
        if name not in self._asked:
            self._asked.append(name)
        p = self._props.get(name)
        if p is None:
            if default is REQUIRED:
                raise SceneError(f"missing required property '{name}' ({tags[0]}) of {self.owner}",
                                 self.owner_location)
            return None
        if p.tag not in tags:
            raise SceneError(f"property '{name}' is a <{p.tag}>, but {self.owner} expects a <{tags[0]}>",
                             p.location)
        p.used = True
        return p

    def get_float(self, name: str, default: Any = REQUIRED, no_limit: bool = False) -> float:
        """`no_limit`: a <float> written as inf (or infinity) is taken, meaning no limit (a far clip); everywhere
        else it is an error, as any other non-finite number is where the file is read."""
        # Nori-style scenes often write integral values as <integer>; accepting them is harmless.
        p = self._fetch(name, ("float", "integer"), default)
        if p is None:
            return default
        if not no_limit:
            self._finite(p)
        return float(p.value)

    @staticmethod
    def _finite(p: Property) -> None:
        if p.tag == "float" and math.isinf(p.value):
            raise SceneError(f"number '{p.raw or p.value}' of '{p.name}' is infinite; every number in a scene must "
                             f"be finite (only a far clip takes inf, for no limit)", p.location)

    def get_int(self, name: str, default: Any = REQUIRED) -> int:
        p = self._fetch(name, ("integer",), default)
        return default if p is None else p.value

    def get_bool(self, name: str, default: Any = REQUIRED) -> bool:
        p = self._fetch(name, ("boolean",), default)
        return default if p is None else p.value

    def get_string(self, name: str, default: Any = REQUIRED) -> str:
        p = self._fetch(name, ("string",), default)
        return default if p is None else p.value

    def _get_array(self, name: str, tag: str, n: int, default: Any, grey: bool = False):
        tags = _COLOR_TAGS[self.format] if tag == "color" else (tag,)
        p = self._fetch(name, tags, default)
        if p is None:
            if default is None:
                return None
            d = np.array(default, dtype=np.float64).reshape(-1)
            if d.size == 1 and (grey or n == 1):
                d = np.repeat(d, n)
            if d.size != n:
                raise ValueError(f"default of {tag} '{name}' must have {n} numbers, got {d.size}")
            return d
        self._finite(p)
        v = p.value
        if p.tag in ("float", "integer"):   # a Mitsuba colour written as a number: grey
            return np.full(n, float(v))
        if v.size == n:
            return v.copy()
        if grey and v.size == 1:
            return np.repeat(v, n)
        also = " (or 1 for grey)" if grey else ""
        raise SceneError(f"property '{name}' (<{p.tag}>) needs {n} numbers{also}, got {v.size}", p.location)

    def get_point(self, name: str, default: Any = REQUIRED) -> np.ndarray:
        return self._get_array(name, "point", 3, default)

    def get_vector(self, name: str, default: Any = REQUIRED) -> np.ndarray:
        return self._get_array(name, "vector", 3, default)

    def get_color(self, name: str, default: Any = REQUIRED, *, emitter: bool = False,
                  unbounded: bool = False) -> np.ndarray:
        """An RGB colour (one number: grey). A Mitsuba <spectrum> becomes the RGB Mitsuba's RGB variants give it
        where it is used: ``emitter`` for an emitter's radiance or intensity, ``unbounded`` for values that may
        exceed 1 such as an index of refraction (see clrender/scene/spectrum.py)."""
        value = self._get_array(name, "color", 3, default, grey=True)
        p = self._props.get(name)
        if p is not None and p.spectrum is not None:
            from .spectrum import constant_to_rgb, spectrum_to_rgb

            lam, val = p.spectrum
            if lam is None:
                return constant_to_rgb(val, emitter)
            try:
                return spectrum_to_rgb(lam, val, emitter=emitter, unbounded=unbounded)
            except ValueError as e:
                raise SceneError(f"spectrum '{name}': {e}", p.location) from None
        return value

    def get_point2(self, name: str, default: Any = REQUIRED) -> np.ndarray:
        return self._get_array(name, "point", 2, default)

    def get_vector2(self, name: str, default: Any = REQUIRED) -> np.ndarray:
        return self._get_array(name, "vector", 2, default)

    def get_transform(self, name: str, default: Any = None) -> Transform:
        p = self._fetch(name, ("transform",), default)
        if p is None:
            return Transform() if default is None else default
        return p.value
