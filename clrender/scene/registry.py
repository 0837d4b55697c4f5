"""Plugin registry: maps (format, tag, type) such as ("nori", "bsdf", "diffuse") to a class, and instantiates specs.

Each scene format has its own namespace: a Nori file's ``<bsdf type="diffuse">`` and a Mitsuba 3 file's are
different plugins (names, parameters and defaults differ) even where they share a kernel. A class may be
registered in several formats.

A plugin class declares the tags it accepts as nested objects in a ``children`` class attribute and
is constructed as ``cls(props, children, spec)``. This module deliberately imports no plugin modules:
whoever assembles the application imports them, which registers them as a side effect.
"""
from __future__ import annotations

from typing import Callable

from ..errors import SceneError, SourceLocation
from .spec import FORMAT_NAMES, FORMAT_TAGS, PluginSpec

_REGISTRY: dict[tuple[str, str, str], type] = {}


def register(tag: str, type_name: str, fmt: str = "nori") -> Callable[[type], type]:
    """Class decorator registering a plugin for ``<tag type="type_name">`` in files of format ``fmt``
    ("nori" or "mitsuba"); stack two decorators to register one class in both."""
    if fmt not in FORMAT_TAGS:
        raise RuntimeError(f"cannot register for unknown scene format {fmt!r}; expected one of {', '.join(FORMAT_TAGS)}")
    if tag not in FORMAT_TAGS[fmt]:
        raise RuntimeError(f"cannot register for unknown {FORMAT_NAMES[fmt]} object tag {tag!r}; "
                           f"expected one of {', '.join(FORMAT_TAGS[fmt])}")

    def deco(cls: type) -> type:
        key = (fmt, tag, type_name)
        if key in _REGISTRY:
            old = _REGISTRY[key]
            raise RuntimeError(f"{FORMAT_NAMES[fmt]} {tag} type {type_name!r} registered twice: "
                               f"{old.__module__}.{old.__qualname__} and {cls.__module__}.{cls.__qualname__}")
        _REGISTRY[key] = cls
        return cls

    return deco


def unregister(tag: str, type_name: str, fmt: str = "nori") -> None:
    """Remove a registration (for tests that register throwaway plugins)."""
    _REGISTRY.pop((fmt, tag, type_name), None)


def snapshot() -> tuple:
    """Every registration as it is now: a cheap key for caches of what is derived from the registry."""
    return tuple(_REGISTRY.items())


def registered(tag: str, fmt: str | None = "nori") -> list[str]:
    """Known type names for ``tag`` in format ``fmt`` (None: in any format), sorted."""
    return sorted({t for (f, g, t) in _REGISTRY if g == tag and (fmt is None or f == fmt)})


def registered_classes(tag: str) -> list[type]:
    """Every class registered for ``tag`` in any format (each once), in (format, type name) order."""
    out = []
    for key in sorted(k for k in _REGISTRY if k[1] == tag):
        if _REGISTRY[key] not in out:
            out.append(_REGISTRY[key])
    return out


def lookup(tag: str, type_name: str, location: SourceLocation | None = None, fmt: str = "nori") -> type:
    try:
        return _REGISTRY[(fmt, tag, type_name)]
    except KeyError:
        known = ", ".join(registered(tag, fmt)) or "(none registered)"
        reader = f" (read as a {FORMAT_NAMES[fmt]} scene)" if fmt != "nori" else ""
        raise SceneError(f"unknown {tag} type '{type_name}'{reader}; known: {known}", location) from None


def instantiate(tag: str, type_name: str, props: dict | None = None, location: SourceLocation | None = None,
                fmt: str = "nori"):
    """Make a plugin from code as if a file of format ``fmt`` had written ``<tag type="type_name">`` with
    ``props`` ({name: (property tag, value)}); unknown types and unused properties are errors, as in a file."""
    from .properties import PropertyList
    from .spec import describe

    plist = PropertyList(describe(tag, type_name), location, fmt=fmt)
    for name, (ptag, value) in (props or {}).items():
        plist.add(name, ptag, value)
    return create(PluginSpec(tag, type_name, None, plist, [], location, format=fmt))


#: what Mitsuba scenes declare participating media with (clrender/media/, clrender/volumes/)
MEDIA_TAGS = ("medium", "phase", "volume")


def _typed(spec) -> str:
    return f' type="{spec.type}"' if getattr(spec, "type", None) else ""


def create(spec: PluginSpec, _made: dict | None = None):
    """Instantiate ``spec`` and, first, its nested objects; then reject unused properties. A spec that occurs
    several times in the tree (a Mitsuba ``<ref>``) becomes one object."""
    if _made is None:
        _made = {}
    if id(spec) in _made:
        return _made[id(spec)]
    cls = lookup(spec.tag, spec.type, spec.location, spec.format)
    accepted = tuple(getattr(cls, "children", ()))
    # Check every nesting before building anything, so the reported error is the structural one
    # rather than some failure deep inside an earlier child.
    for i, child in enumerate(spec.children):
        if child.tag == "volume" and child.tag not in accepted:
            raise SceneError(f"<volume{_typed(child)}> cannot be nested in {spec.describe()}: volumes (grid or "
                             "constant) are the sigma_t or albedo of a <medium type=\"heterogeneous\">",
                             child.location)
        if child.tag in MEDIA_TAGS and child.tag not in accepted:
            where = ("a <phase> belongs in a <medium>" if child.tag == "phase" else
                     "a <medium> belongs in a <shape> (name=\"interior\" or \"exterior\"), in the <sensor>, or at "
                     "the top level of a Mitsuba 3 scene, referenced from those")
            raise SceneError(f"<{child.tag}{_typed(child)}> cannot be nested in {spec.describe()}: {where}",
                             child.location)
        if child.tag not in accepted:
            takes = (", ".join(f"<{t}>" for t in accepted) if accepted else "no nested objects")
            ref = spec.refs.get(i)
            if ref is not None:   # the ref is the mistake, not the object it names
                what = f"parameter '{ref.name}' of {spec.describe()}" if ref.name else spec.describe()
                rule = f"accepts {takes} only" if accepted else "takes no nested objects"
                raise SceneError(f"{ref.describe()}: {what} gets '{ref.id}', a {child.describe()} (declared at "
                                 f"{child.location}), but {spec.describe()} {rule}", ref.location)
            raise SceneError(f"<{child.tag}> cannot be nested in {spec.describe()} (it accepts {takes})",
                             child.location)
    children = [create(child, _made) for child in spec.children]
    obj = cls(spec.props, children, spec)
    spec.props.check_unused()
    try:
        obj.spec = spec
    except AttributeError:  # a plugin with __slots__ and no 'spec' slot: nothing to attach to
        pass
    _made[id(spec)] = obj
    return obj
