"""Reader for Nori's XML scene format (a root ``<scene>`` without attributes, or a test file's ``<test type="ttest|
chi2test">``), producing PluginSpecs of format "nori" in the Nori dialect asked for (:mod:`clrender.scene.dialect`).

It stands on :mod:`clrender.scene.xmlbase` (pass one, values, substitution) and accepts Nori's structure:

- object tags ``mesh bsdf emitter camera integrator sampler rfilter texture ...`` (:data:`~clrender.scene.spec.
  OBJECT_TAGS`) with exactly a ``type`` (a ``texture`` also its ``name``);
- property tags ``integer float boolean string point vector color transform`` with ``name`` and ``value``; a
  ``filename`` string resolves against the scene file's folder;
- ``<default name value>`` directly inside the root: the value of ``$name`` unless ``-D`` gives one;
- ``<transform>`` ops ``translate scale rotate lookat matrix``, each with exactly its attributes (``rotate`` takes
  ``axis`` and ``angle``; upstream Nori normalises the axis, the ETH dialect does not).
"""
from __future__ import annotations

import os
from typing import Mapping

from ..errors import SceneError, SourceLocation
from . import dialect as _dialect
from .properties import PROPERTY_TAGS, PropertyList
from .spec import OBJECT_TAGS, PluginSpec, describe
from .transform import Transform
from .xmlbase import OP_TAGS, Elem, Source, XmlBuilder, check_defines_used, check_filename, tags

ROOT_TAGS = ("scene", "test")
TEST_TYPES = ("ttest", "chi2test")

_OP_ATTRS = {
    "translate": ("value",),
    "scale": ("value",),
    "matrix": ("value",),
    "rotate": ("axis", "angle"),
    "lookat": ("origin", "target", "up"),
}


class NoriBuilder(XmlBuilder):
    """Pass two for a Nori file (or a Nori test file, ``<test type="ttest|chi2test">``)."""

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


def build(src: Source, root: Elem, defines: Mapping[str, str] | None, base_dir: str,
          nori_dialect: str | None = None) -> PluginSpec:
    """Pass two for a Nori file whose pass-one tree is ``root``; ``nori_dialect`` as :func:`clrender.scene.dialect.
    resolve` takes it."""
    builder = NoriBuilder(src, defines, base_dir, _dialect.resolve(nori_dialect))
    spec = builder.build_root(root)
    check_defines_used(builder.user_defines, builder.used_defines, src.filename)
    return spec
