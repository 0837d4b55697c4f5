"""Plugin registry: maps (tag, type) such as ("bsdf", "diffuse") to a class, and instantiates specs.

A plugin class declares the tags it accepts as nested objects in a ``children`` class attribute and
is constructed as ``cls(props, children, spec)``. This module deliberately imports no plugin modules:
whoever assembles the application imports them, which registers them as a side effect.
"""
from __future__ import annotations

from typing import Callable

from ..errors import SceneError, SourceLocation
from .spec import OBJECT_TAGS, PluginSpec

_REGISTRY: dict[tuple[str, str], type] = {}


def register(tag: str, type_name: str) -> Callable[[type], type]:
    """Class decorator registering a plugin for ``<tag type="type_name">``."""
    if tag not in OBJECT_TAGS:
        raise RuntimeError(f"cannot register for unknown object tag {tag!r}; "
                           f"expected one of {', '.join(OBJECT_TAGS)}")

    def deco(cls: type) -> type:
        key = (tag, type_name)
        if key in _REGISTRY:
            old = _REGISTRY[key]
            raise RuntimeError(f"{tag} type {type_name!r} registered twice: "
                               f"{old.__module__}.{old.__qualname__} and {cls.__module__}.{cls.__qualname__}")
        _REGISTRY[key] = cls
        return cls

    return deco


def unregister(tag: str, type_name: str) -> None:
    """Remove a registration (for tests that register throwaway plugins)."""
    _REGISTRY.pop((tag, type_name), None)


def registered(tag: str) -> list[str]:
    """Known type names for ``tag``, sorted."""
    return sorted(t for (g, t) in _REGISTRY if g == tag)


def lookup(tag: str, type_name: str, location: SourceLocation | None = None) -> type:
    try:
        return _REGISTRY[(tag, type_name)]
    except KeyError:
        known = ", ".join(registered(tag)) or "(none registered)"
        raise SceneError(f"unknown {tag} type '{type_name}'; known: {known}", location) from None


def instantiate(tag: str, type_name: str, props: dict | None = None, location: SourceLocation | None = None):
    """Make a plugin from code as if a file had written ``<tag type="type_name">`` with ``props``
    ({name: (property tag, value)}); unknown types and unused properties are errors, as in a file."""
    from .properties import PropertyList
    from .spec import describe

    plist = PropertyList(describe(tag, type_name), location)
    for name, (ptag, value) in (props or {}).items():
        plist.add(name, ptag, value)
    return create(PluginSpec(tag, type_name, None, plist, [], location))


def create(spec: PluginSpec):
    """Instantiate ``spec`` and, first, its nested objects; then reject unused properties."""
    cls = lookup(spec.tag, spec.type, spec.location)
    accepted = tuple(getattr(cls, "children", ()))
    # Check every nesting before building anything, so the reported error is the structural one
    # rather than some failure deep inside an earlier child.
    for child in spec.children:
        if child.tag not in accepted:
            takes = (", ".join(f"<{t}>" for t in accepted) if accepted else "no nested objects")
            raise SceneError(f"<{child.tag}> cannot be nested in {spec.describe()} (it accepts {takes})",
                             child.location)
    children = [create(child) for child in spec.children]
    obj = cls(spec.props, children, spec)
    spec.props.check_unused()
    try:
        obj.spec = spec
    except AttributeError:  # a plugin with __slots__ and no 'spec' slot: nothing to attach to
        pass
    return obj
