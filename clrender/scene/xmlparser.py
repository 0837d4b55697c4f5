"""The XML scene readers' front door: a Nori or Mitsuba scene file (or string) to a :class:`PluginSpec` tree.

Pass one (:mod:`clrender.scene.xmlbase`) reads the bytes into a located element tree; its root picks the builder of
pass two: a ``<scene version="...">`` is Mitsuba's (:mod:`clrender.scene.mitsuba_xml`), anything else Nori's
(:mod:`clrender.scene.nori_xml`, whose ``<scene>`` takes no attributes and which also reads ``<test>`` files).
"""
from __future__ import annotations

import os
import stat
from typing import Mapping

from ..errors import SceneError
from . import mitsuba_xml, nori_xml
from .spec import PluginSpec
# FLOAT_MAX: callers (plugins on other branches among them) import it from here, where it used to live
from .xmlbase import FLOAT_MAX, read_bytes

__all__ = ["parse_file", "parse_string", "FLOAT_MAX"]


def _parse_bytes(data: bytes, filename: str, defines, base_dir: str, force_encoding: str | None,
                 nori_dialect: str | None = None) -> PluginSpec:
    src, root = read_bytes(data, filename, force_encoding)
    if mitsuba_xml.is_mitsuba_root(root):  # <scene version="..."> is Mitsuba's; Nori's <scene> has no attributes
        return mitsuba_xml.build(src, root, defines, base_dir)
    return nori_xml.build(src, root, defines, base_dir, nori_dialect)


def parse_file(path, defines: Mapping[str, str] | None = None, nori_dialect: str | None = None) -> PluginSpec:
    """Parse a Nori or Mitsuba 3 XML file (the root tells which). ``defines`` fill ``$name`` in attribute values (overriding <default>);
    ``nori_dialect`` is ``upstream`` or ``eth`` (see :mod:`clrender.scene.dialect`; None: the default)."""
    path = os.fspath(path)
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):  # a FIFO or device would block or never end
            raise SceneError(f"cannot read scene file '{path}': not a regular file")
        with open(path, "rb") as f:
            data = f.read()
    except OSError as e:
        raise SceneError(f"cannot read scene file '{path}': {e.strerror or e}") from None
    return _parse_bytes(data, path, defines, os.path.dirname(os.path.abspath(path)), None, nori_dialect)


def parse_string(text: str | bytes, filename: str = "<string>", defines: Mapping[str, str] | None = None,
                 base_dir: str | None = None, nori_dialect: str | None = None) -> PluginSpec:
    """Parse XML text. Relative filenames resolve against ``base_dir``, else the folder of
    ``filename`` if that names a real path, else the current directory."""
    if base_dir is None:
        if filename.startswith("<"):
            base_dir = os.getcwd()
        else:
            base_dir = os.path.dirname(os.path.abspath(filename))
    if isinstance(text, str):
        return _parse_bytes(text.encode("utf-8"), filename, defines, base_dir, "UTF-8", nori_dialect)
    return _parse_bytes(text, filename, defines, base_dir, None, nori_dialect)
