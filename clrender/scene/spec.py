"""The parsed, not yet instantiated form of one scene object (an element like ``<bsdf type=...>``)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterator

from ..errors import SourceLocation
from .properties import PropertyList

OBJECT_TAGS = ("scene", "mesh", "bsdf", "emitter", "camera", "integrator", "sampler", "rfilter",
               "test", "texture", "medium", "phase")
#: object tags of Mitsuba 3's scene format
MITSUBA_OBJECT_TAGS = ("scene", "shape", "bsdf", "emitter", "sensor", "film", "rfilter", "sampler", "integrator",
                       "texture", "medium", "phase", "volume", "spectrum")
#: the object tags of each scene format the registry keeps a namespace for
FORMAT_TAGS = {"nori": OBJECT_TAGS, "mitsuba": MITSUBA_OBJECT_TAGS}
#: how messages name each format
FORMAT_NAMES = {"nori": "Nori", "mitsuba": "Mitsuba 3"}


@dataclass(frozen=True)
class RefSite:
    """A ``<ref id="..." name="...">`` element: where it is written and what it says."""

    location: SourceLocation | None
    id: str
    name: str | None

    def describe(self) -> str:
        name = f' name="{self.name}"' if self.name is not None else ""
        return f'<ref id="{self.id}"{name}>'


@dataclass(eq=False)
class PluginSpec:
    """One object element: its tag, ``type`` (``"scene"`` for ``<scene>``), optional ``name``,
    properties, nested objects in document order, where its start tag is, and the dialect it was read in."""

    tag: str
    type: str
    name: str | None
    props: PropertyList
    children: list["PluginSpec"] = field(default_factory=list)
    location: SourceLocation | None = None
    #: the Nori dialect the file was read in ("upstream", "eth" or "eth2023"; see clrender.scene.dialect)
    dialect: str = "upstream"
    #: the scene format the file was read as ("nori" or "mitsuba"); picks the registry's namespace
    format: str = "nori"
    #: children that a Mitsuba ``<ref>`` put here, by index into ``children``: the ref's own element (its
    #: location, id and name), so that an error about such a child can point at the ref, not at the declaration
    refs: dict[int, "RefSite"] = field(default_factory=dict)

    def describe(self) -> str:
        """How errors refer to this object, e.g. ``<bsdf type="diffuse">``."""
        return describe(self.tag, self.type)

    def children_with_tag(self, tag: str) -> list["PluginSpec"]:
        return [c for c in self.children if c.tag == tag]

    def walk(self) -> Iterator["PluginSpec"]:
        """This spec and all its descendants, depth first in document order."""
        yield self
        for c in self.children:
            yield from c.walk()

    def __repr__(self) -> str:
        name = f" name={self.name!r}" if self.name is not None else ""
        return (f"PluginSpec(<{self.tag} type={self.type!r}{name}> at {self.location}, "
                f"{len(self.props)} props, {len(self.children)} children)")


def describe(tag: str, type_name: str) -> str:
    return "<scene>" if tag == "scene" else f'<{tag} type="{type_name}">'
