"""Reader for Nori's XML scene format, producing a :class:`PluginSpec` tree.

The work is done in two passes. Pass one runs expat and builds a bare element tree in which every
element remembers the byte offset of its start tag (ElementTree forgets positions). Pass two checks
the structure strictly (known tags only, exact attribute sets, no stray text), substitutes ``$name``
defines in attribute values, and parses every property value eagerly, so that every mistake is
reported as ``file:line:col: message`` at the place it was written.

Line and column numbers are computed from byte offsets into the file bytes we handed to expat; the
XML declaration is blanked out (not removed) when whitespace precedes it, so offsets stay those of
the original file.
"""
from __future__ import annotations

import os
import stat
from typing import Mapping

from ..errors import SceneError, SourceLocation
from . import dialect as _dialect
from .properties import PROPERTY_TAGS, PropertyList
from .spec import OBJECT_TAGS, PluginSpec, describe
from .transform import Transform
from .xmlbase import FLOAT_MAX, OP_TAGS, Elem, Source, XmlBuilder, check_defines_used, check_filename, read_bytes, tags

__all__ = ["parse_file", "parse_string", "FLOAT_MAX"]

ROOT_TAGS = ("scene", "test")
TEST_TYPES = ("ttest", "chi2test")

_OP_ATTRS = {
    "translate": ("value",),
    "scale": ("value",),
    "matrix": ("value",),
    "rotate": ("axis", "angle"),
    "lookat": ("origin", "target", "up"),
}

# --------------------------------------------------------------------------------------------------
# Pass two: element tree -> PluginSpec
# --------------------------------------------------------------------------------------------------
class _Builder(XmlBuilder):
    def __init__(self, src: Source, defines: Mapping[str, str] | None, base_dir: str, dialect: str):
        self.user_defines = {str(k): str(v) for k, v in (defines or {}).items()}
        super().__init__(src, dict(self.user_defines), set())
        self.dialect = dialect
        self.base_dir = base_dir

    # --- structure ------------------------------------------------------------------------------
    def build_root(self, el: Elem) -> PluginSpec:
        if el.tag not in ROOT_TAGS:
            raise SceneError(f"the root element must be <scene> or <test type=\"ttest|chi2test\">, "
                             f"not <{el.tag}>", el.loc)
        file_defaults: dict[str, tuple[str, SourceLocation]] = {}
        for c in el.children:
            if c.tag != "default":
                continue
            name, value = self.default_attrs(c)
            if name in file_defaults:
                first = file_defaults[name][1]
                raise SceneError(f"<default> '{name}' given twice (first at line {first.line})", c.loc)
            if c.children:
                raise SceneError(f"<{c.children[0].tag}> cannot be nested in <default>", c.children[0].loc)
            file_defaults[name] = (value, c.loc)
        self.defines = {k: v for k, (v, _) in file_defaults.items()}
        self.defines.update(self.user_defines)
        return self.build_object(el, is_root=True)

    def build_object(self, el: Elem, is_root: bool = False) -> PluginSpec:
        if el.tag == "scene":
            self.attrs(el, ())
            type_name, name = "scene", None
        elif el.tag == "texture":
            a = self.attrs(el, ("type", "name"))
            type_name, name = a["type"], a["name"]
        else:
            type_name, name = self.attrs(el, ("type",))["type"], None
        if is_root and el.tag == "test" and type_name not in TEST_TYPES:
            raise SceneError(f"unknown test type '{type_name}'; known: {', '.join(TEST_TYPES)}",
                             self.attr_loc(el, "type"))
        props = PropertyList(describe(el.tag, type_name), el.loc)
        spec = PluginSpec(el.tag, type_name, name, props, [], el.loc, self.dialect)
        for c in el.children:
            if c.tag in OBJECT_TAGS:
                spec.children.append(self.build_object(c))
            elif c.tag in PROPERTY_TAGS:
                self.build_property(c, props)
            elif c.tag == "default":
                if not is_root:
                    raise SceneError("<default> is only allowed directly inside the root element", c.loc)
            elif c.tag in OP_TAGS:
                raise self.op_outside_transform(c)
            else:
                extra = ", or <default>" if is_root else ""
                hint = ""
                if c.tag in ("shape", "sensor", "film", "rgb", "spectrum", "ref", "include"):
                    hint = ('; <' + c.tag + '> is Mitsuba 3\'s: a Mitsuba scene\'s root is <scene version="3.0.0">, '
                            'and this file\'s <scene> has no version, so it is read as a Nori scene')
                raise SceneError(f"unknown tag <{c.tag}> in <{el.tag}>; expected an object "
                                 f"({tags(OBJECT_TAGS)}) or a property ({tags(PROPERTY_TAGS)}){extra}{hint}",
                                 c.loc)
        return spec

    def build_property(self, el: Elem, props: PropertyList) -> None:
        if el.tag == "transform":
            name = self.attrs(el, ("name",))["name"]
            props.add(name, "transform", self.build_transform(el), el.loc)
            return
        a = self.attrs(el, ("name", "value"))
        name, text = a["name"], a["value"]
        value = self.value_of(el, el.tag, text)
        if el.tag == "string" and name == "filename":
            check_filename(value, self.attr_loc(el, "value"))
            value = os.path.normpath(os.path.join(self.base_dir, value))
        self.no_children(el)
        props.add(name, el.tag, value, el.loc, raw=text)

    def transform_op(self, op: Elem) -> Transform:
        if op.tag not in OP_TAGS:
            known = "" if op.tag in OBJECT_TAGS or op.tag in PROPERTY_TAGS else "unknown tag "
            raise SceneError(f"{known}<{op.tag}> is not allowed in <transform>; expected one of "
                             f"{tags(OP_TAGS)}", op.loc)
        a = self.attrs(op, _OP_ATTRS[op.tag])
        if op.tag == "translate":
            step = Transform.translate(self.numbers(op, "value", a["value"], (3,)))
        elif op.tag == "scale":
            step = self.checked(op, Transform.scale, self.numbers(op, "value", a["value"], (3, 1)))
        elif op.tag == "matrix":
            step = self.checked(op, Transform.from_rows, self.numbers(op, "value", a["value"], (16,)))
        elif op.tag == "rotate":
            axis = self.numbers(op, "axis", a["axis"], (3,))
            angle = self.one_float(op, "angle", a["angle"])
            step = self.checked(op, Transform.rotate, axis, angle, _dialect.normalizes_rotate_axis(self.dialect))
        else:
            step = self.lookat(op, *(self.numbers(op, k, a[k], (3,)) for k in ("origin", "target", "up")))
        self.no_children(op)
        return step


# --------------------------------------------------------------------------------------------------
# Public entry points
# --------------------------------------------------------------------------------------------------
def _parse_bytes(data: bytes, filename: str, defines, base_dir: str, force_encoding: str | None,
                 nori_dialect: str | None = None) -> PluginSpec:
    src, root = read_bytes(data, filename, force_encoding)
    from . import mitsuba_xml

    if mitsuba_xml.is_mitsuba_root(root):  # <scene version="..."> is Mitsuba's; Nori's <scene> has no attributes
        return mitsuba_xml.build(src, root, defines, base_dir)
    dialect = _dialect.resolve(nori_dialect)
    builder = _Builder(src, defines, base_dir, dialect)
    spec = builder.build_root(root)
    check_defines_used(builder.user_defines, builder.used_defines, filename)
    return spec


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
