"""What the XML scene readers share: the located element tree (pass one) and a builder base (pass two's attribute,
value and transform machinery), on which the Nori builder (:mod:`clrender.scene.nori_xml`) and the Mitsuba builder
(:mod:`clrender.scene.mitsuba_xml`) stand; :mod:`clrender.scene.xmlparser` picks one by the file's root.

Pass one runs expat and builds a bare element tree in which every element remembers the byte offset of its start tag
(ElementTree forgets positions). Pass two, in a builder, checks the structure strictly (known tags only, exact
attribute sets, no stray text), substitutes ``$name`` defines in attribute values, and parses every property value
eagerly, so that every mistake is reported as ``file:line:col: message`` at the place it was written.

Line and column numbers are computed from byte offsets into the file bytes we handed to expat; the XML declaration
is blanked out (not removed) when whitespace precedes it, so offsets stay those of the original file.
"""
from __future__ import annotations

import abc
import bisect
import codecs
import logging
import math
import re
from dataclasses import dataclass, field
from typing import Mapping
from xml.parsers import expat

import numpy as np

from ..errors import SceneError, SourceLocation
from .transform import Transform

log = logging.getLogger("clrender")

OP_TAGS = ("translate", "scale", "rotate", "lookat", "matrix")
_XML_WS = b" \t\r\n"
_VAR = re.compile(r"\$([A-Za-z_][A-Za-z0-9_]*)")
_NUM_SPLIT = re.compile(r"[\s,]+")
#: the largest finite float32: the device computes in float, where a larger number becomes infinite
FLOAT_MAX = float(np.finfo(np.float32).max)
_INT = re.compile(r"[+-]?[0-9]+")
_ATTR = re.compile(rb"""([^\s=/<>"']+)\s*=\s*("[^"]*"|'[^']*')""")
_DECL_ENCODING = re.compile(rb"""encoding\s*=\s*["']([A-Za-z0-9._-]+)["']""")


def tags(names) -> str:
    return ", ".join(f"<{n}>" for n in names)


def quoted(names) -> str:
    if not names:
        return "no attributes"
    return ", ".join(f"'{n}'" for n in names)


# --------------------------------------------------------------------------------------------------
# Pass one: bytes -> located element tree
# --------------------------------------------------------------------------------------------------
class Source:
    """The bytes given to expat, with offset -> (line, column) mapping.

    Columns count characters, not bytes. Each line's byte -> column table is built once, when the line is
    first asked about, so a whole scene written on one long line still loads in linear time.
    """

    def __init__(self, data: bytes, filename: str, encoding: str | None):
        self.data = data
        self.filename = filename
        self.encoding = encoding or "utf-8"
        try:
            self._utf8 = codecs.lookup(self.encoding).name == "utf-8"
        except LookupError:
            self._utf8 = False
        self._newlines = [m.start() for m in re.finditer(b"\n", data)]
        self._line_columns: dict[int, np.ndarray | None] = {}

    def _columns(self, line: int, start: int) -> np.ndarray | None:
        """Characters before each byte of line ``line`` (None: the line is ASCII, bytes are columns)."""
        if line not in self._line_columns:
            end = self._newlines[line] if line < len(self._newlines) else len(self.data)
            raw = np.frombuffer(self.data, np.uint8, end - start, start)
            table = None
            if raw.size and raw.max() >= 0x80:
                if self._utf8:
                    starts = (raw & 0xC0) != 0x80   # UTF-8: every byte but a continuation starts a character
                else:
                    text = self.data[start:end].decode(self.encoding, errors="replace")
                    starts = np.zeros(raw.size, bool)
                    pos = 0
                    for ch in text:   # other encodings: map each character back to its first byte
                        if pos < raw.size:
                            starts[pos] = True
                        pos += max(1, len(ch.encode(self.encoding, errors="replace")))
                table = np.concatenate(([0], np.cumsum(starts)))
            self._line_columns[line] = table
        return self._line_columns[line]

    def loc(self, offset: int) -> SourceLocation:
        offset = max(0, min(offset, len(self.data)))
        line = bisect.bisect_left(self._newlines, offset)  # newlines strictly before offset
        start = self._newlines[line - 1] + 1 if line else 0
        table = self._columns(line, start)
        col = offset - start if table is None else int(table[min(offset - start, table.size - 1)])
        return SourceLocation(self.filename, line + 1, col + 1)


@dataclass(eq=False)
class Elem:
    tag: str
    attrs: dict[str, str]
    offset: int
    loc: SourceLocation
    children: list["Elem"] = field(default_factory=list)


def _prepare(data: bytes) -> tuple[bytes, str | None, bool]:
    """Make leading whitespace before ``<?xml`` acceptable to expat without moving any byte.

    Returns (data, declared encoding, whether the declaration was blanked out).
    """
    start = len(codecs.BOM_UTF8) if data.startswith(codecs.BOM_UTF8) else 0
    body = data[start:]
    stripped = body.lstrip(_XML_WS)
    encoding = None
    if stripped.startswith(b"<?xml"):
        end = stripped.find(b"?>")
        if end >= 0:
            decl = stripped[: end + 2]
            m = _DECL_ENCODING.search(decl)
            encoding = m.group(1).decode("ascii") if m else None
            if len(stripped) != len(body):
                pos = start + len(body) - len(stripped)
                blank = bytes(b if b in b"\r\n" else 0x20 for b in decl)
                return data[:pos] + blank + data[pos + len(decl):], encoding, True
    return data, encoding, False


#: Deeper nesting than any scene needs; the builder recurses once per level.
MAX_DEPTH = 200


def _read_tree(src: Source, expat_encoding: str | None) -> Elem:
    parser = expat.ParserCreate(expat_encoding)
    stack: list[Elem] = []
    roots: list[Elem] = []

    def start(tag, attrs):
        off = parser.CurrentByteIndex
        el = Elem(tag, attrs, off, src.loc(off))
        if len(stack) >= MAX_DEPTH:
            raise SceneError(f"elements are nested more than {MAX_DEPTH} deep (at <{tag}>); "
                             f"a scene needs only a few levels", el.loc)
        (stack[-1].children if stack else roots).append(el)
        stack.append(el)

    def end(tag):
        stack.pop()

    def chars(text):
        stripped = text.strip(" \t\r\n")
        if not stripped:
            return
        off = parser.CurrentByteIndex
        # Point at the first non-blank byte; expat's offset is where this text run begins.
        while 0 <= off < len(src.data) and src.data[off] in _XML_WS:
            off += 1
        shown = stripped if len(stripped) <= 30 else stripped[:27] + "..."
        raise SceneError(f"unexpected text {shown!r} inside <{stack[-1].tag}>; only elements, "
                         f"comments and whitespace may appear here", src.loc(off))

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    try:
        parser.Parse(src.data, True)
    except expat.ExpatError as e:
        off = parser.ErrorByteIndex
        if off is not None and off >= 0:
            loc = src.loc(off)
        else:
            loc = SourceLocation(src.filename, e.lineno, e.offset + 1)
        raise SceneError(f"malformed XML: {expat.ErrorString(e.code)}", loc) from None
    return roots[0]


def read_bytes(data: bytes, filename: str, force_encoding: str | None) -> tuple[Source, Elem]:
    """Pass one for any of the XML scene formats: the located element tree of ``data``."""
    data, declared, blanked = _prepare(data)
    encoding = force_encoding or declared
    if encoding is not None:
        try:
            codecs.lookup(encoding)
        except LookupError:
            raise SceneError(f"unknown encoding '{encoding}' in the XML declaration; use UTF-8",
                             SourceLocation(filename, 1, 1)) from None
    src = Source(data, filename, encoding)
    return src, _read_tree(src, encoding if (force_encoding or blanked) else None)


# --------------------------------------------------------------------------------------------------
# Pass two: what both builders do with an element
# --------------------------------------------------------------------------------------------------
class XmlBuilder(abc.ABC):
    """The located reading of attributes, ``$name`` substitution, values and transforms, for a builder of one
    format. ``defines`` fill ``$name``; ``used_defines`` collects every ``$name`` the file asked for (whether -D or a
    <default> filled it); a builder may share both with others (the Mitsuba builder's included files)."""

    def __init__(self, src: Source, defines: dict[str, str], used_defines: set[str]):
        self.src = src
        self.defines = defines
        self.used_defines = used_defines

    # --- locations ------------------------------------------------------------------------------
    def attr_loc(self, el: Elem, name: str, *, at_value: bool = True) -> SourceLocation:
        """Where attribute ``name`` (its value, or its name) is written in ``el``'s start tag."""
        data = self.src.data
        end, quote = el.offset, None
        while end < len(data):
            c = data[end]
            if quote is not None:
                if c == quote:
                    quote = None
            elif c in (0x22, 0x27):
                quote = c
            elif c == 0x3E:
                break
            end += 1
        want = name.encode(self.src.encoding, errors="replace")
        for m in _ATTR.finditer(data, el.offset, end):
            if m.group(1) == want:
                return self.src.loc(m.start(2) + 1 if at_value else m.start(1))
        return el.loc

    # --- attributes -----------------------------------------------------------------------------
    def attrs(self, el: Elem, expected: tuple[str, ...], *, substitute: bool = True) -> dict[str, str]:
        """Check that ``el`` has exactly the attributes ``expected`` and return their values."""
        for name in el.attrs:
            if name not in expected:
                raise SceneError(f"unexpected attribute '{name}' in <{el.tag}>; it takes "
                                 f"{quoted(expected)}", self.attr_loc(el, name, at_value=False))
        for name in expected:
            if name not in el.attrs:
                raise SceneError(f"<{el.tag}> is missing the required attribute '{name}' "
                                 f"(it takes {quoted(expected)})", el.loc)
        if not substitute:
            return {n: el.attrs[n] for n in expected}
        return {n: self.substitute(el, n) for n in expected}

    def substitute(self, el: Elem, name: str) -> str:
        value = el.attrs[name]
        if "$" not in value:
            return value

        def replace(m: re.Match) -> str:
            var = m.group(1)
            self.used_defines.add(var)
            if var not in self.defines:
                raise SceneError(
                    f"undefined variable '${var}' in attribute {name}=\"{value}\" of <{el.tag}>; "
                    f"pass -D {var}=value (or add <default name=\"{var}\" value=\"...\"/> to the file)",
                    self.attr_loc(el, name))
            return self.defines[var]

        return _VAR.sub(replace, value)

    def default_attrs(self, el: Elem) -> tuple[str, str]:
        """A ``<default name value>``'s name and value. Default values are taken literally: they are the base layer
        of substitution."""
        a = self.attrs(el, ("name", "value"), substitute=False)
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", a["name"]):
            raise SceneError(f"<default> name '{a['name']}' is not a valid variable name", self.attr_loc(el, "name"))
        return a["name"], a["value"]

    @staticmethod
    def _describe(el) -> str:
        name = el.attrs.get("name")
        return f'<{el.tag} name="{name}">' if name else f"<{el.tag}>"

    # --- values ---------------------------------------------------------------------------------
    def numbers(self, el: Elem, attr: str, text: str, counts: tuple[int, ...] | None = None,
                spelled_inf: bool = False) -> np.ndarray:
        """The numbers of an attribute, each finite and within float32's range. `spelled_inf`: also +inf written as
        such (inf, infinity), which the property's getter refuses unless it means "no limit" there."""
        tag = self._describe(el)
        tokens = [t for t in _NUM_SPLIT.split(text.strip()) if t]
        if not tokens:
            raise SceneError(f"attribute {attr}=\"{text}\" of {tag} is empty; expected numbers "
                             f"separated by commas and/or spaces", self.attr_loc(el, attr))
        values = []
        for t in tokens:
            try:
                values.append(float(t))
            except ValueError:
                raise SceneError(f"bad number '{t}' in attribute {attr}=\"{text}\" of {tag}; "
                                 f"expected numbers separated by commas and/or spaces",
                                 self.attr_loc(el, attr)) from None
            if spelled_inf and values[-1] == math.inf and t.lower().lstrip("+") in ("inf", "infinity"):
                continue
            if not math.isfinite(values[-1]):
                what = "not a number" if math.isnan(values[-1]) else "infinite (or too large for a float)"
                raise SceneError(f"number '{t}' in attribute {attr}=\"{text}\" of {tag} is {what}; "
                                 f"every number in a scene must be finite", self.attr_loc(el, attr))
            if abs(values[-1]) > FLOAT_MAX:
                raise SceneError(f"number '{t}' in attribute {attr}=\"{text}\" of {tag} is too large: the "
                                 f"renderer computes in single precision, whose numbers stop at about "
                                 f"{FLOAT_MAX:.4g}", self.attr_loc(el, attr))
        if counts is not None and len(values) not in counts:
            want = " or ".join(str(c) for c in counts)
            raise SceneError(f"attribute {attr}=\"{text}\" of {tag} needs {want} "
                             f"number{'s' if counts != (1,) else ''}, got {len(values)}",
                             self.attr_loc(el, attr))
        return np.array(values, dtype=np.float64)

    def one_float(self, el: Elem, attr: str, text: str, spelled_inf: bool = False) -> float:
        return float(self.numbers(el, attr, text, (1,), spelled_inf)[0])

    def value_of(self, el: Elem, tag: str, text: str):
        if tag == "boolean":
            low = text.strip().lower()
            if low not in ("true", "false"):
                raise SceneError(f"bad boolean value=\"{text}\" in <boolean>; expected true or false",
                                 self.attr_loc(el, "value"))
            return low == "true"
        if tag == "integer":
            if not _INT.fullmatch(text.strip()):
                raise SceneError(f"bad integer value=\"{text}\" in <integer>; expected a whole number",
                                 self.attr_loc(el, "value"))
            return int(text.strip())
        if tag == "float":
            return self.one_float(el, "value", text, spelled_inf=True)
        if tag == "string":
            return text
        # point / vector / color: the getter checks the count, since it depends on the use (3 or 2).
        return self.numbers(el, "value", text)

    # --- structure ------------------------------------------------------------------------------
    def no_children(self, el: Elem) -> None:
        if el.children:
            c = el.children[0]
            raise SceneError(f"<{c.tag}> cannot be nested in <{el.tag}>, which takes no nested elements",
                             c.loc)

    @staticmethod
    def op_outside_transform(el: Elem) -> SceneError:
        return SceneError(f"<{el.tag}> is a transform op and is only allowed inside <transform>", el.loc)

    # --- transforms -----------------------------------------------------------------------------
    def build_transform(self, el: Elem) -> Transform:
        result = Transform()
        for op in el.children:
            result = self.transform_op(op) @ result  # each op is left-multiplied onto the ones before it
        return result

    @abc.abstractmethod
    def transform_op(self, op: Elem) -> Transform:
        """The transform of one child of a ``<transform>`` (the format's ops and their attributes): each format's
        builder (nori_xml.py, mitsuba_xml.py) defines its own."""

    def lookat(self, op: Elem, origin, target, up) -> Transform:
        warnings: list[str] = []
        step = self.checked(op, Transform.lookat, origin, target, up, warnings)
        for w in warnings:
            log.warning("%s: %s", op.loc, w)
        return step

    @staticmethod
    def checked(op: Elem, fn, *args) -> Transform:
        try:
            return fn(*args)
        except ValueError as e:
            raise SceneError(f"<{op.tag}>: {e}", op.loc) from None


def check_defines_used(defines: Mapping[str, str], used: set[str], filename: str) -> None:
    """A -D value that fills no ``$name`` is a mistake (a typo, the wrong scene): an error, as Mitsuba 3.9 stops
    with "Found unused parameters", whether or not a <default> declares the name."""
    unused = [f"{k}={v}" for k, v in defines.items() if k not in used]
    if unused:
        asks = ", ".join(f"${n}" for n in sorted(used)) or "no $name at all"
        raise SceneError(f"-D {', -D '.join(unused)}: the scene has no such $name to fill (it uses {asks})",
                         SourceLocation(filename))


def check_filename(value: str, location: SourceLocation) -> None:
    """An empty filename would resolve to the scene's own folder and be reported as "a folder, not a file"."""
    if not value.strip():
        raise SceneError('<string name="filename"> is empty; expected the path of a file', location)
