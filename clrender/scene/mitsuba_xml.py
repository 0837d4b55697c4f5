"""Reader for Mitsuba 3's XML scene format (a root ``<scene version="2.x|3.x">``), producing PluginSpecs of format
"mitsuba". Older files (``version="0.x|1.x"``) are upgraded object by object as Mitsuba 3 upgrades them
(:mod:`clrender.scene.mitsuba_legacy`).

It shares pass one (bytes -> located element tree) and the value parsing with the Nori reader
(:mod:`clrender.scene.xmlbase`) and differs in the structure it accepts:

- object tags ``shape bsdf emitter sensor film rfilter sampler integrator texture ...`` with ``type`` and optional
  ``id`` and ``name`` (the parameter a nested object fills, e.g. ``<texture name="reflectance">``);
- property tags ``float integer boolean string point vector rgb spectrum transform``; ``point``/``vector`` take
  ``value`` or ``x y z``; a ``spectrum`` is a constant (grey) or a ``wavelength:value`` list, turned into the
  RGB that Mitsuba's RGB variants compute (:mod:`clrender.scene.spectrum`);
- ``<ref id="..."/>`` (``<ref name="..." id="..."/>`` for a named parameter) to an object declared with that
  ``id`` anywhere in the scene, before or after the ref (as Mitsuba 3.9 resolves refs once the whole scene is read;
  a ref to an id that never comes and a cycle of refs are located errors); ``<alias id as>`` (of an id declared
  before it, as in Mitsuba);
- ``<include filename="..."/>``: the included file's root ``<scene>`` children are spliced in where the include
  is written; ``<path value="folder"/>`` (a child of a file's root) adds a folder to the resolver. Relative paths
  are resolved as Mitsuba 3.9 resolves them (:class:`_State`);
- ``<transform>`` ops ``translate scale rotate lookat matrix``; ``rotate`` axes are used as written (not
  normalised), as Mitsuba does.
"""
from __future__ import annotations

import logging
import os
import re
import stat
from dataclasses import replace

import numpy as np

from ..errors import SceneError, SourceLocation
from .properties import MITSUBA_PROPERTY_TAGS, PropertyList
from .spec import MITSUBA_OBJECT_TAGS, PluginSpec, RefSite, describe
from .transform import Transform
from . import mitsuba_legacy as _legacy
from .xmlbase import OP_TAGS, XmlBuilder, check_defines_used, check_filename, quoted, read_bytes, tags

_VERSION = re.compile(r"([0-9]+)\.([0-9]+)(\.([0-9]+))?")
_ID = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*")
#: Mitsuba 3.9's limit (ParserConfig::max_include_depth): the main file is depth 0, a file it includes depth 1,
#: and a file at this depth is refused, so the same chains load in both
MAX_INCLUDE_DEPTH = 15
READER = "Mitsuba 3 reader"
log = logging.getLogger("clrender")


def is_mitsuba_root(el) -> bool:
    """A root ``<scene>`` with a ``version`` attribute is a Mitsuba scene (Nori's <scene> takes no attributes)."""
    return el.tag == "scene" and "version" in el.attrs


class _State:
    """What every file of one scene shares: defines, declared ids, the resolver's folders, the include chain.

    ``folders`` is Mitsuba 3.9's FileResolver while a file is read: a relative path is looked for in each folder
    in turn, then in the current directory, and the first that exists wins. It starts as the main file's folder;
    ``<path>`` puts its folder first; an ``<include>`` is looked for, and its file read, with the including file's
    folder put first, and the list as it was comes back after it (so a ``<path>`` in an included file serves the
    includes below it only). Meshes, images and other files are resolved when the whole scene is read, as Mitsuba
    builds its plugins then: with the main file's list, a ``<path>`` written after the shape included. All checked
    against Mitsuba 3.9.1 (tests/test_mitsuba_format.py).
    """

    def __init__(self, defines, main_dir: str):
        self.user_defines = {str(k): str(v) for k, v in (defines or {}).items()}
        self.defines = dict(self.user_defines)
        self.file_defaults: dict[str, SourceLocation] = {}
        self.used_defines: set[str] = set()
        self.ids: dict[str, PluginSpec] = {}
        self.main_dir = main_dir
        self.folders = [main_dir]
        self.chain: list[str] = []
        #: the filename properties, resolved once the whole scene is read
        self.filenames: list[tuple[PropertyList, str]] = []
        #: refs to ids not declared yet: (the spec holding the ref, its child index, the id, where the id is written);
        #: the child is a stand-in until the whole scene is read
        self.forward: list[tuple[PluginSpec, int, str, SourceLocation]] = []

    def looked_in(self) -> list[str]:
        return list(dict.fromkeys(self.folders + [os.getcwd()]))

    def find(self, name: str) -> str | None:
        """The first existing ``folder/name`` of the resolver (``name`` itself if absolute), else None."""
        name = os.path.expanduser(name)
        if os.path.isabs(name):
            return os.path.normpath(name) if os.path.exists(name) else None
        for d in self.looked_in():
            p = os.path.join(d, name)
            if os.path.exists(p):
                return os.path.normpath(p)
        return None

    def resolve(self, name: str) -> str:
        """``find``, else the name relative to the main file's folder (which the caller reports as missing)."""
        found = self.find(name)
        return found if found is not None else os.path.normpath(os.path.join(self.main_dir,
                                                                             os.path.expanduser(name)))

    def resolve_filenames(self) -> None:
        for props, name in self.filenames:
            entry = props._entry(name)
            entry.value = self.resolve(entry.value)


class MitsubaBuilder(XmlBuilder):
    """Pass two for one Mitsuba file; includes get a builder of their own sharing ``state``."""

    def __init__(self, src, state: _State, folder: str | None = None):
        super().__init__(src, state.defines, state.used_defines)
        #: the folder of this builder's file (the main file's: the scene's base folder)
        self.folder = folder or state.main_dir
        #: a file older than Mitsuba 2.0, upgraded as Mitsuba 3 reads it (mitsuba_legacy.py)
        self.legacy = False
        self.state = state

    @staticmethod
    def err(message: str, loc) -> SceneError:
        return SceneError(message, loc)

    # --- root -----------------------------------------------------------------------------------
    def build_root(self, el) -> PluginSpec:
        self.check_version(el)
        spec = PluginSpec("scene", "scene", None, PropertyList("<scene>", el.loc, fmt="mitsuba"), [], el.loc,
                          format="mitsuba")
        self.read_defaults(el)
        self.fill(el, spec, is_root=True)
        return spec

    def check_version(self, el) -> None:
        self.attrs(el, ("version",))
        v = el.attrs["version"]
        m = _VERSION.fullmatch(v.strip())
        if not m:
            raise self.err(f'bad scene version="{v}"; expected major.minor[.patch], e.g. "3.0.0"',
                           self.attr_loc(el, "version"))
        if m.group(1) not in ("0", "1", "2", "3"):
            raise self.err(f"unsupported 'version' \"{v}\" of <scene>: clrender reads Nori scenes (whose <scene> "
                           f"has no attributes) and Mitsuba 0.x to 3.x scenes", self.attr_loc(el, "version",
                                                                                            at_value=False))
        self.legacy = int(m.group(1)) < 2

    def param_name(self, name: str) -> str:
        """A parameter's name as Mitsuba 3 reads it: an old file's camelCase becomes snake_case."""
        return _legacy.camel_to_snake(name) if self.legacy else name

    def read_defaults(self, el) -> None:
        for c in el.children:
            if c.tag != "default":
                continue
            name, value = self.default_attrs(c)
            first = self.state.file_defaults.get(name)
            if first is not None and first.file == c.loc.file:
                raise self.err(f"<default> '{name}' given twice (first at {first})", c.loc)
            self.no_children(c)
            if first is not None:   # an included file's default for a name already given: the first wins, as in
                continue            # Mitsuba 3.9.1 (mitsuba-data's participating_media tests and their preamble)
            self.state.file_defaults[name] = c.loc
            if name not in self.state.user_defines:  # -D wins over the file's default
                self.defines[name] = value

    # --- objects --------------------------------------------------------------------------------
    def object_attrs(self, el) -> tuple[str, str | None, str | None]:
        for name in el.attrs:
            if name not in ("type", "id", "name"):
                raise self.err(f"unexpected attribute '{name}' in <{el.tag}>; it takes 'type', 'id', 'name'",
                               self.attr_loc(el, name, at_value=False))
        if "type" not in el.attrs:
            raise self.err(f"<{el.tag}> is missing the required attribute 'type'", el.loc)
        type_name = self.substitute(el, "type")
        oid = self.substitute(el, "id") if "id" in el.attrs else None
        name = self.param_name(self.substitute(el, "name")) if "name" in el.attrs else None
        return type_name, oid, name

    def build_object(self, el, is_root: bool = False) -> PluginSpec:
        type_name, oid, name = self.object_attrs(el)
        props = PropertyList(describe(el.tag, type_name), el.loc, fmt="mitsuba")
        spec = PluginSpec(el.tag, type_name, name, props, [], el.loc, format="mitsuba")
        wrapper = self.legacy and el.tag == "integrator" and type_name in _legacy.WRAPPERS
        if self.legacy and el.tag == "integrator" and not wrapper:
            from .registry import registered

            _legacy.check_integrator(type_name, self.attr_loc(el, "type"), registered("integrator", "mitsuba"))
        self.fill(el, spec)
        if wrapper:
            spec = _legacy.unwrap(spec, self.attr_loc(el, "type"))
        elif self.legacy:
            _legacy.upgrade(spec, set(spec.refs))
        if oid is not None:
            self.declare(oid, spec, el)
        return spec

    def declare(self, oid: str, spec: PluginSpec, el, attr: str = "id") -> None:
        first = self.state.ids.get(oid)
        if first is not None:
            raise self.err(f"id '{oid}' is declared twice (first at {first.location})", self.attr_loc(el, attr))
        self.state.ids[oid] = spec

    def fill(self, el, spec: PluginSpec, is_root: bool = False) -> None:
        for c in el.children:
            if c.tag == "spectrum" and "type" not in c.attrs:   # <spectrum name value>: a property
                self.build_property(c, spec.props)
            elif c.tag in MITSUBA_OBJECT_TAGS and c.tag != "scene":
                spec.children.append(self.build_object(c))
            elif c.tag in MITSUBA_PROPERTY_TAGS or (c.tag == "srgb" and self.legacy):
                self.build_property(c, spec.props)
            elif c.tag == "ref":
                target = self.build_ref(c)
                oid = self.substitute(c, "id")
                spec.refs[len(spec.children)] = RefSite(c.loc, oid,
                                                        self.substitute(c, "name") if "name" in c.attrs else None)
                if target is None:   # declared further on (or never): resolved once the whole scene is read
                    self.state.forward.append((spec, len(spec.children), oid, self.attr_loc(c, "id")))
                    name = self.param_name(self.substitute(c, "name")) if "name" in c.attrs else None
                    target = PluginSpec("ref", oid, name, PropertyList(f'<ref id="{oid}">', c.loc), [], c.loc,
                                        format="mitsuba")
                spec.children.append(target)
            elif c.tag == "include":
                self.build_include(c, spec)
            elif c.tag == "alias":
                a = self.attrs(c, ("id", "as"))
                self.no_children(c)
                if a["id"] not in self.state.ids:
                    raise self.unknown_id(c, a["id"])
                self.declare(a["as"], self.state.ids[a["id"]], c, "as")
            elif c.tag == "default":
                if not is_root:
                    raise self.err("<default> is only allowed directly inside the root <scene>", c.loc)
            elif c.tag == "path":
                if not is_root:
                    raise self.err("<path> is only allowed directly inside a file's root <scene> (as in Mitsuba)",
                                   c.loc)
                self.add_path(c)
            elif c.tag in OP_TAGS:
                raise self.op_outside_transform(c)
            else:
                extra = ", <default>, <path>" if is_root else ""
                hint = ""
                if c.tag == "srgb":
                    hint = ("; <srgb> (an sRGB-encoded colour) is Mitsuba 0.x's: write it as an <rgb> of linear "
                            "values, or give the file the version it was written for")
                if c.tag in ("mesh", "camera", "color"):
                    hint = (f"; <{c.tag}> is Nori's: this file is read as a Mitsuba 3 scene because its <scene> has "
                            f"a version attribute (Nori's <scene> has none)")
                raise self.err(f"unknown tag <{c.tag}> in <{el.tag}>; expected an object "
                               f"({tags(t for t in MITSUBA_OBJECT_TAGS if t != 'scene')}), a property "
                               f"({tags(MITSUBA_PROPERTY_TAGS)}), <ref>, <include>, <alias>{extra}{hint}", c.loc)

    def add_path(self, el) -> None:
        """``<path value="folder"/>``: the folder goes first in the resolver. A relative one is the folder beside
        this file, else one the resolver finds (as Mitsuba 3.9.1 reads it)."""
        value = self.attrs(el, ("value",))["value"]
        self.no_children(el)
        folder = os.path.expanduser(value)
        if not os.path.isabs(folder):
            beside = os.path.join(self.folder, folder)
            folder = beside if os.path.exists(beside) else (self.state.find(folder) or beside)
        if not os.path.exists(folder):
            raise self.err(f"<path>: folder '{value}' not found (looked beside this file and in "
                           f"{', '.join(self.state.looked_in())})", self.attr_loc(el, "value"))
        self.state.folders = [os.path.normpath(folder)] + self.state.folders

    def unknown_id(self, el, oid: str) -> SceneError:
        """An <alias> of an id not declared before it (Mitsuba 3.9 refuses it too)."""
        known = ", ".join(sorted(self.state.ids)) or "none"
        return self.err(f"<alias> of unknown id '{oid}' (an alias must come after the object it names; declared so "
                        f"far: {known})", self.attr_loc(el, "id"))

    def build_ref(self, el) -> PluginSpec:
        for name in el.attrs:
            if name not in ("id", "name"):
                raise self.err(f"unexpected attribute '{name}' in <ref>; it takes 'id' and optionally 'name'",
                               self.attr_loc(el, name, at_value=False))
        if "id" not in el.attrs:
            raise self.err("<ref> is missing the required attribute 'id'", el.loc)
        self.no_children(el)
        oid = self.substitute(el, "id")
        target = self.state.ids.get(oid)
        if target is None:
            return None
        return _referenced(target, self.param_name(self.substitute(el, "name")) if "name" in el.attrs else None)

    def build_include(self, el, spec: PluginSpec) -> None:
        a = self.attrs(el, ("filename",))
        self.no_children(el)
        outer = self.state.folders
        self.state.folders = [self.folder] + outer
        try:
            self.read_include(el, a["filename"], spec)
        finally:
            self.state.folders = outer

    def read_include(self, el, filename: str, spec: PluginSpec) -> None:
        path = self.state.resolve(filename)
        if path in self.state.chain:
            raise self.err(f"<include> of '{filename}' includes itself (include chain: "
                           f"{' -> '.join(self.state.chain + [path])})", self.attr_loc(el, "filename"))
        if len(self.state.chain) >= MAX_INCLUDE_DEPTH:
            raise self.err(f"<include> of '{filename}' reaches the maximum include depth, {MAX_INCLUDE_DEPTH} "
                           f"(Mitsuba 3's: includes nest at most {MAX_INCLUDE_DEPTH - 1} deep; include chain: "
                           f"{' -> '.join(self.state.chain[:2] + ['...'] + self.state.chain[-2:] + [path])})",
                           self.attr_loc(el, "filename"))
        try:
            if not stat.S_ISREG(os.stat(path).st_mode):
                raise self.err(f"cannot include '{filename}' ({path}): not a regular file",
                               self.attr_loc(el, "filename"))
            with open(path, "rb") as f:
                data = f.read()
        except OSError as e:
            raise self.err(f"cannot include '{filename}': {e.strerror or e} (looked in "
                           f"{', '.join(self.state.looked_in())})", self.attr_loc(el, "filename")) from None
        src, root = read_bytes(data, path, None)
        sub = MitsubaBuilder(src, self.state, os.path.dirname(path))
        if root.tag != "scene":
            raise sub.err(f"an included file must have a <scene> root, not <{root.tag}>", root.loc)
        sub.check_version(root)
        self.state.chain.append(path)
        try:
            sub.read_defaults(root)
            sub.fill(root, spec, is_root=True)
        finally:
            self.state.chain.pop()

    # --- properties -----------------------------------------------------------------------------
    def xyz(self, el, default: float) -> np.ndarray:
        """A point/vector/translate/scale written as value="..." or as x, y, z attributes."""
        names = [n for n in el.attrs if n in ("x", "y", "z")]
        if "value" in el.attrs and names:
            raise self.err(f"<{el.tag}> takes either 'value' or 'x', 'y', 'z', not both",
                           self.attr_loc(el, names[0], at_value=False))
        if "value" in el.attrs:
            return self.numbers(el, "value", self.substitute(el, "value"), (3, 1) if el.tag == "scale" else (3,))
        return np.array([self.one_float(el, n, self.substitute(el, n)) if n in el.attrs else default
                         for n in ("x", "y", "z")])

    def build_property(self, el, props: PropertyList) -> None:
        if el.tag == "transform":
            name = self.param_name(self.attrs(el, ("name",))["name"])
            props.add(name, "transform", self.build_transform(el), el.loc)
            return
        if el.tag in ("point", "vector"):
            allowed = ("name", "value", "x", "y", "z")
            for n in el.attrs:
                if n not in allowed:
                    raise self.err(f"unexpected attribute '{n}' in <{el.tag}>; it takes 'name' and 'value' "
                                   f"(or 'x', 'y', 'z')", self.attr_loc(el, n, at_value=False))
            if "name" not in el.attrs:
                raise self.err(f"<{el.tag}> is missing the required attribute 'name'", el.loc)
            self.no_children(el)
            props.add(self.param_name(self.substitute(el, "name")), el.tag, self.xyz(el, 0.0), el.loc)
            return
        if el.tag == "spectrum" and "filename" in el.attrs:
            self.attrs(el, ("name", "filename"))
            raise self.err("<spectrum filename=...> (a spectrum file) is not supported; write the spectrum as "
                           'value="wavelength:value, ..." or as an <rgb>', el.loc)
        a = self.attrs(el, ("name", "value"))
        self.no_children(el)
        name, text = self.param_name(a["name"]), a["value"]
        tag = el.tag
        if el.tag == "srgb":   # Mitsuba 0.x: "#rrggbb" or numbers, sRGB-encoded; an <rgb> of their linear values
            tag = "rgb"
            try:
                value = _legacy.srgb_to_linear(text)
            except ValueError:
                value = _legacy.srgb_to_linear(self.numbers(el, "value", text, (3, 1)))
        elif el.tag == "rgb":
            value = self.numbers(el, "value", text, (3, 1))
            value = np.repeat(value, 3) if value.size == 1 else value
        elif el.tag == "spectrum":
            pairs = self.spectrum(el, text)
            value = self.spectrum_rgb(pairs)
        else:
            value = self.value_of(el, el.tag, text)
        props.add(name, tag, value, el.loc, raw=text)
        if el.tag == "string" and name == "filename":
            check_filename(value, self.attr_loc(el, "value"))
            self.state.filenames.append((props, name))
        if el.tag == "spectrum":
            props._entry(name).spectrum = pairs

    @staticmethod
    def spectrum_rgb(pairs) -> np.ndarray:
        """The reflectance-context RGB (the getter recomputes it where the spectrum is used)."""
        from .spectrum import constant_to_rgb, spectrum_to_rgb

        lam, val = pairs
        return constant_to_rgb(val) if lam is None else spectrum_to_rgb(lam, val, warn=False)

    def spectrum(self, el, text: str) -> tuple:
        """(wavelengths, values) of a ``wavelength:value`` list, or (None, constant)."""
        from .spectrum import check_spectrum

        if ":" not in text:
            v = self.numbers(el, "value", text)
            if v.size != 1:
                raise self.err(f'<spectrum value="{text}"> is neither one constant (a grey value) nor a list of '
                               f'wavelength:value pairs such as "400:0.1, 700:0.5"', self.attr_loc(el, "value"))
            return None, float(v[0])
        pairs = [p for p in re.split(r"[\s,]+", text.strip()) if p]
        lam, val = [], []
        for p in pairs:
            parts = p.split(":")
            try:
                if len(parts) != 2:
                    raise ValueError
                lam.append(float(parts[0]))
                val.append(float(parts[1]))
            except ValueError:
                raise self.err(f"bad wavelength:value pair '{p}' in <spectrum value=\"{text}\">; expected "
                               f'pairs like "400:0.1, 500:0.3" (nanometres, increasing)',
                               self.attr_loc(el, "value")) from None
        try:
            check_spectrum(np.array(lam), np.array(val))
            return np.array(lam), np.array(val)
        except ValueError as e:
            raise self.err(f"<spectrum value=\"{text}\">: {e}", self.attr_loc(el, "value")) from None

    def transform_op(self, op) -> Transform:
        if op.tag == "lookAt" and self.legacy:   # old files' spelling; Mitsuba 3 knows only <lookat>
            op = replace(op, tag="lookat")
        if op.tag not in OP_TAGS:
            hint = " (<lookAt> is how Mitsuba 0.x files spell it)" if op.tag == "lookAt" else ""
            raise self.err(f"<{op.tag}> is not allowed in <transform>; expected one of {tags(OP_TAGS)}{hint}", op.loc)
        self.no_children(op)
        if op.tag == "translate":
            self.op_attrs(op, ("value", "x", "y", "z"))
            return Transform.translate(self.xyz(op, 0.0))
        if op.tag == "scale":
            self.op_attrs(op, ("value", "x", "y", "z"))
            return self.checked(op, Transform.scale, self.xyz(op, 1.0))
        if op.tag == "matrix":
            a = self.attrs(op, ("value",))
            v = self.numbers(op, "value", a["value"], (16, 9))
            if v.size == 9:
                m = np.eye(4)
                m[:3, :3] = v.reshape(3, 3)
                v = m.reshape(-1)
            return self.checked(op, Transform.from_rows, v)
        if op.tag == "rotate":
            self.op_attrs(op, ("value", "x", "y", "z", "angle"))
            if "angle" not in op.attrs:
                raise self.err("<rotate> is missing the required attribute 'angle'", op.loc)
            axis = self.xyz(op, 0.0)
            angle = self.one_float(op, "angle", self.substitute(op, "angle"))
            return self.checked(op, Transform.rotate, axis, angle, False)
        self.op_attrs(op, ("origin", "target", "up"))
        for k in ("origin", "target"):
            if k not in op.attrs:
                raise self.err(f"<lookat> is missing the required attribute '{k}'", op.loc)
        origin, target = (self.numbers(op, k, self.substitute(op, k), (3,)) for k in ("origin", "target"))
        up = self.numbers(op, "up", self.substitute(op, "up"), (3,)) if "up" in op.attrs else np.zeros(3)
        if not up.any():   # none given (or zero): Mitsuba's choice, a vector perpendicular to the view
            d = target - origin
            up = _frame_vector(d / np.linalg.norm(d)) if d.any() else up
        return self.lookat(op, origin, target, up)

    def op_attrs(self, op, allowed) -> None:
        for n in op.attrs:
            if n not in allowed:
                raise self.err(f"unexpected attribute '{n}' in <{op.tag}>; it takes {quoted(allowed)}",
                               self.attr_loc(op, n, at_value=False))


def _referenced(target: PluginSpec, name: str | None) -> PluginSpec:
    """What a ``<ref>`` with parameter name ``name`` to ``target`` puts into its parent."""
    if name is None or name == target.name or target.tag not in ("texture", "medium", "volume"):
        return target   # one object wherever it is referenced (a bsdf's or emitter's name says nothing)
    # A medium's name says on which side of a shape it is (interior, exterior), a volume's which parameter of a
    # heterogeneous medium it fills (sigma_t, albedo): a spec under that name, as below.
    # A texture filling another parameter (its name tells the BSDF which): a spec sharing the texture's
    # properties and children under that name.
    return replace(target, name=name)


def _resolve_forward(state: _State, root: PluginSpec) -> None:
    """Put the objects that refs to later ids name in place of their stand-ins, then refuse a cycle of refs (which
    only such a ref can close), as Mitsuba 3.9.1's parser does once the whole scene is read."""
    if not state.forward:
        return
    for spec, index, oid, loc in state.forward:
        target = state.ids.get(oid)
        if target is None:
            known = ", ".join(sorted(state.ids)) or "none"
            raise SceneError(f"reference to unknown id '{oid}': no object in the scene is declared with that id "
                             f"(declared: {known})", loc)
        # the stand-in's name, which an old file's upgrade may have renamed since
        spec.children[index] = _referenced(target, spec.children[index].name)
    # a texture a named ref renamed is a copy sharing its target's children list: objects are told by that list
    names: dict[int, str] = {}
    for oid, spec in state.ids.items():
        names.setdefault(id(spec.children), oid)
    done: set[int] = set()

    def visit(spec: PluginSpec, path: list[PluginSpec]) -> None:
        for i, child in enumerate(spec.children):
            start = next((k for k, p in enumerate(path) if p.children is child.children), None)
            if start is not None:
                cycle = [names.get(id(p.children), p.describe()) for p in path[start:]]
                ref = spec.refs.get(i)
                raise SceneError(f"circular reference: {' -> '.join(cycle + [cycle[0]])} (an object cannot "
                                 f"contain itself)", ref.location if ref is not None else child.location)
            if id(child.children) not in done:
                visit(child, path + [child])
        done.add(id(spec.children))

    visit(root, [root])


#: what a scene declares at its top level only for refs to use: referenced nowhere, it cannot change the image
_DECLARATIONS = ("bsdf", "texture", "medium", "volume", "phase")
#: Mitsuba 3.9.1's plugins of those kinds (each checked with its PluginManager.plugin_type): a type outside these is
#: an error in Mitsuba too, used or not
_MITSUBA_TYPES = {
    "bsdf": ("blendbsdf", "bumpmap", "circular", "conductor", "dielectric", "diffuse", "hair", "mask", "measured",
             "measured_polarized", "normalmap", "null", "plastic", "polarizer", "pplastic", "principled",
             "principledthin", "retarder", "roughconductor", "roughdielectric", "roughplastic", "thindielectric",
             "twosided"),
    "texture": ("bitmap", "checkerboard", "mesh_attribute", "volume"),
    "volume": ("constvolume", "gridvolume"),
    "phase": ("blendphase", "hg", "isotropic", "rayleigh", "sggx", "tabphase"),
    "medium": ("heterogeneous", "homogeneous"),
}


def leave_out_unbuildable_unused(root: PluginSpec) -> None:
    """Leave out, with a warning, each object declared at the scene's top level (a bsdf, texture, medium, volume or
    phase), referenced nowhere, that holds a Mitsuba 3 plugin type clrender lacks: Mitsuba builds it and renders the
    scene as if it were not there (the Mitsuba tutorials' lego scene declares a `diffuse` with a `volume` texture
    that no shape uses). One that is referenced, a type Mitsuba does not have either (a typo), and any other error
    in an unused one stay errors. Called by the loader once every plugin is registered."""
    from .registry import registered

    used = {id(c.children) for s in root.walk() for i, c in enumerate(s.children) if i in s.refs}
    keep, refs = [], {}
    for i, c in enumerate(root.children):
        lacking = None
        if c.tag in _DECLARATIONS and i not in root.refs and id(c.children) not in used:
            lacking = next((d for d in c.walk() if d.type not in registered(d.tag, "mitsuba")), None)
        if lacking is not None and lacking.type not in _MITSUBA_TYPES.get(lacking.tag, ()):
            lacking = None      # Mitsuba refuses it too: the error below says so
        if lacking is None:
            if i in root.refs:
                refs[len(keep)] = root.refs[i]
            keep.append(c)
            continue
        held = "" if lacking is c else f" holds {lacking.describe()} (at {lacking.location}), a type clrender lacks,"
        lacks = "" if held else " is a type clrender lacks and"
        log.warning("%s: %s%s%s is referenced nowhere: left out (Mitsuba 3 builds it; the image is the same without "
                    "it)", c.location, c.describe(), held, lacks)
    root.children[:], root.refs = keep, refs


def _frame_vector(n: np.ndarray) -> np.ndarray:
    """The first vector of Mitsuba's coordinate_system(n) (Duff et al. 2017): the up <lookat> takes when none is
    written."""
    sign = 1.0 if n[2] >= 0 else -1.0
    a = -1.0 / (sign + n[2])
    return np.array([1.0 + sign * n[0] * n[0] * a, sign * n[0] * n[1] * a, -sign * n[0]])


def build(src, root, defines, main_dir: str) -> PluginSpec:
    """Pass two for a Mitsuba scene whose pass-one tree is ``root``."""
    state = _State(defines, main_dir)
    state.chain.append(os.path.normpath(os.path.abspath(src.filename)) if not src.filename.startswith("<")
                       else src.filename)
    try:
        spec = MitsubaBuilder(src, state).build_root(root)
        _resolve_forward(state, spec)
        state.resolve_filenames()
        check_defines_used(state.user_defines, state.used_defines, src.filename)
        return spec
    except SceneError as e:
        raise SceneError(with_reader(e.message), e.location) from None


def with_reader(message: str) -> str:
    """``message`` saying that the Mitsuba 3 reader read the file (once)."""
    return message if READER in message else f"{message} [{READER}]"
