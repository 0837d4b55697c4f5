"""Wavefront OBJ loading with Nori's semantics.

Supported statements: `v x y z`, `vt u v`, `vn x y z` and `f` with corners `v`, `v/vt`, `v//vn`,
`v/vt/vn`, including negative indices (relative to what has been defined so far: -1 is the latest).
Polygons are triangulated as a fan (1,2,3), (1,3,4), ... Everything else (`o g s usemtl mtllib l vp`,
comments, blank lines, unknown statements) is ignored; extra numbers on `v`/`vt`/`vn` lines (vertex colours,
a `w` component) are ignored as well.

De-indexing follows Nori: every distinct (v, vt, vn) triple used by a face becomes one output vertex, in
order of first use. `normals` is None when no face corner references a `vn`; if only some corners do, the
others get the geometric normal of their triangle (such a corner becomes a vertex of its own per triangle,
so neighbouring triangles do not share a made-up normal). `uvs` is None when no corner references a `vt`;
corners without one get (0, 0).

Speed: the common case is parsed in bulk with numpy (lines bucketed by prefix, numbers converted by
`np.fromstring`, face corners decoded from a byte array). Whenever anything looks unusual or wrong, the
loader falls back to a careful line-by-line parser, which is the authority on semantics and which reports
errors with the OBJ line number.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from clrender.errors import SceneError, SourceLocation
from clrender.shapes.meshdata import MeshData
from clrender.shapes.meshfile import numpy_text_errors, read_mesh_bytes

__all__ = ["load_obj"]


def load_obj(path, location: SourceLocation | None = None) -> MeshData:
    """Load an OBJ file into a de-indexed, fan-triangulated `MeshData` (object space).

    `location` is where the scene referenced the file; it is used for errors about the file as a whole
    not being readable. Errors inside the file name the OBJ file and line.
    """
    path = os.fspath(path)
    data = read_mesh_bytes(path, "OBJ", location)
    if data.startswith(b"\xef\xbb\xbf"):
        # a UTF-8 byte order mark (Windows editors write one): left in, it hides the first statement
        data = data[3:]
    elif data.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise SceneError("OBJ file is UTF-16 encoded; save it as ASCII or UTF-8", SourceLocation(path, 1))

    parsed = None
    try:
        parsed = _parse_fast(data)
    except (_NeedSlowPath, ValueError, UnicodeDecodeError, IndexError):
        parsed = None
    if parsed is None:
        parsed = _parse_slow(data, path)
    if parsed.counts.size == 0:
        raise SceneError("OBJ file contains no faces (expected at least one 'f' statement)",
                         SourceLocation(path))
    return _build(parsed)


# --------------------------------------------------------------------------------------------------
# Intermediate representation shared by both parsers


@dataclass
class _Parsed:
    positions: np.ndarray  # (nv, 3) float64
    uvs: np.ndarray  # (nt, 2) float64
    normals: np.ndarray  # (nn, 3) float64
    v: np.ndarray  # (C,) int64 0-based position index per face corner
    t: np.ndarray  # (C,) int64 0-based uv index, -1 if absent
    n: np.ndarray  # (C,) int64 0-based normal index, -1 if absent
    counts: np.ndarray  # (F,) corners per polygon


class _NeedSlowPath(Exception):
    """The bulk parser saw something it does not handle; the careful parser decides what it means."""


# --------------------------------------------------------------------------------------------------
# Fast path

_FAST_PREFIXES = (b"v ", b"vt ", b"vn ", b"f ")
_KEYWORDS = {b"v", b"vt", b"vn", b"f"}


def _parse_fast(data: bytes) -> _Parsed:
    lines = data.split(b"\n")
    vl = [ln[2:] for ln in lines if ln[:2] == b"v "]
    tl = [ln[3:] for ln in lines if ln[:3] == b"vt "]
    nl = [ln[3:] for ln in lines if ln[:3] == b"vn "]
    fl = [ln[2:] for ln in lines if ln[:2] == b"f "]
    # Lines that do not start with an exact fast prefix may still be statements we care about
    # (leading blanks, tab separators); those files take the careful path.
    for ln in [ln for ln in lines if not ln.startswith(_FAST_PREFIXES)]:
        head = ln.split(None, 1)
        if head and head[0] in _KEYWORDS:
            raise _NeedSlowPath

    positions = _floats_block(vl, 3)
    uvs = _floats_block(tl, 2)
    normals = _floats_block(nl, 3)
    if not (np.isfinite(positions).all() and np.isfinite(uvs).all() and np.isfinite(normals).all()):
        raise _NeedSlowPath  # the careful parser names the line with the NaN/Inf
    if not fl:
        return _Parsed(positions, uvs, normals, *(np.zeros(0, np.int64) for _ in range(4)))

    v, t, n, has_t, has_n, counts = _faces_block(fl)
    if np.any(counts < 3):
        raise _NeedSlowPath
    if np.any(v == 0) or np.any(has_t & (t == 0)) or np.any(has_n & (n == 0)):
        raise _NeedSlowPath

    negative = (v < 0) | (has_t & (t < 0)) | (has_n & (n < 0))
    nv, nt, nn = len(positions), len(uvs), len(normals)
    if np.any(negative):
        # Relative indices count the definitions made before the face's own line.
        line_kind = {b"v ": [], b"vt ": [], b"vn ": [], b"f ": []}
        for i, ln in enumerate(lines):
            if ln[:2] == b"v ":
                line_kind[b"v "].append(i)
            elif ln[:2] == b"f ":
                line_kind[b"f "].append(i)
            elif ln[:3] in (b"vt ", b"vn "):
                line_kind[ln[:3]].append(i)
        face_line = np.repeat(np.asarray(line_kind[b"f "], np.int64), counts)
        before_v = np.searchsorted(np.asarray(line_kind[b"v "], np.int64), face_line)
        before_t = np.searchsorted(np.asarray(line_kind[b"vt "], np.int64), face_line)
        before_n = np.searchsorted(np.asarray(line_kind[b"vn "], np.int64), face_line)
        v = np.where(v < 0, v + before_v + 1, v)
        t = np.where(t < 0, t + before_t + 1, t)
        n = np.where(n < 0, n + before_n + 1, n)
        if np.any(v <= 0) or np.any(has_t & (t <= 0)) or np.any(has_n & (n <= 0)):
            raise _NeedSlowPath
    if np.any(v > nv) or np.any(has_t & (t > nt)) or np.any(has_n & (n > nn)):
        raise _NeedSlowPath

    return _Parsed(
        positions, uvs, normals,
        v - 1,
        np.where(has_t, t - 1, -1),
        np.where(has_n, n - 1, -1),
        counts,
    )


def _floats_block(lines: list[bytes], need: int) -> np.ndarray:
    """(len(lines), need) float64 from lines with at least `need` numbers each (extra ones ignored)."""
    if not lines:
        return np.zeros((0, need), np.float64)
    block = b"\n".join(lines)
    if b"#" in block:
        raise _NeedSlowPath  # trailing comments: let the careful parser strip them
    values = _numbers(block, np.float64)
    if values.size == need * len(lines):
        # Equal totals could still hide a short line next to a long one; verify per line.
        counts = _token_counts(np.frombuffer(block, np.uint8), len(lines))[0]
        if np.all(counts == need):
            return values.reshape(-1, need)
    else:
        counts = _token_counts(np.frombuffer(block, np.uint8), len(lines))[0]
    if counts.sum() != values.size or np.any(counts < need):
        raise _NeedSlowPath
    starts = np.cumsum(counts) - counts
    return values[starts[:, None] + np.arange(need)[None, :]]


def _numbers(block: bytes, dtype) -> np.ndarray:
    """The numbers of a whitespace-separated block; ValueError at a bad token (load_obj then parses carefully)."""
    with numpy_text_errors():
        return np.fromstring(block, dtype=dtype, sep=" ")


def _token_counts(b: np.ndarray, nlines: int):
    """Whitespace-separated tokens per line of a '\\n'-joined block, and the token start offsets."""
    newline = b == 10
    blank = newline | (b == 32) | (b == 9) | (b == 13)
    start = ~blank
    start[1:] &= blank[:-1]
    starts = np.flatnonzero(start)
    # searchsorted over the sparse positions is far cheaper than a cumsum over every byte.
    line_of = np.searchsorted(np.flatnonzero(newline), starts)
    counts = np.bincount(line_of, minlength=nlines)
    return counts, starts, blank


_FACE_BYTES = np.zeros(256, bool)
_FACE_BYTES[[ord(c) for c in "0123456789-+/ \t\r\n"]] = True


def _faces_block(lines: list[bytes]):
    block = b"\n".join(lines)
    b = np.frombuffer(block, np.uint8)
    if not np.all(_FACE_BYTES[b]):
        raise _NeedSlowPath
    counts, starts, blank = _token_counts(b, len(lines))
    ntok = starts.size
    ends = np.flatnonzero(~blank & np.append(blank[1:], True))
    slash_pos = np.flatnonzero(b == 47)
    nslash = np.bincount(np.searchsorted(starts, slash_pos, side="right") - 1, minlength=ntok)
    double_pos = slash_pos[:-1][np.diff(slash_pos) == 1]
    ndouble = np.bincount(np.searchsorted(starts, double_pos, side="right") - 1, minlength=ntok)
    # Only the four corner shapes 'v', 'v/t', 'v//n', 'v/t/n' are bulk-decoded.
    if (np.any(nslash > 2) or np.any(ndouble > 1) or np.any(b[starts] == 47) or np.any(b[ends] == 47)
            or np.any((ndouble == 1) & (nslash != 2))):
        raise _NeedSlowPath
    spaced = b.copy()
    spaced[slash_pos] = 32
    ints = _numbers(spaced.tobytes(), np.int64)
    nint = nslash + 1 - ndouble
    if ints.size != int(nint.sum()):
        raise _NeedSlowPath
    first = np.cumsum(nint) - nint
    has_t = (nslash >= 1) & (ndouble == 0)
    has_n = nslash == 2
    v = ints[first]
    t = np.zeros(ntok, np.int64)
    t[has_t] = ints[first[has_t] + 1]
    n = np.zeros(ntok, np.int64)
    n[has_n] = ints[first[has_n] + 2 - ndouble[has_n]]
    return v, t, n, has_t, has_n, counts


# --------------------------------------------------------------------------------------------------
# Careful path


_MAX_INDEX = 2**31 - 1  # faces are int32 on the device


def _parse_slow(data: bytes, path: str) -> _Parsed:
    text = data.decode("utf-8", errors="replace")
    pos: list[list[float]] = []
    tex: list[list[float]] = []
    nor: list[list[float]] = []
    v: list[int] = []
    t: list[int] = []
    n: list[int] = []
    counts: list[int] = []
    face_lines: list[int] = []

    def fail(lineno: int, msg: str):
        raise SceneError(msg, SourceLocation(path, lineno))

    def numbers(tokens, need, what, lineno):
        if len(tokens) < need:
            fail(lineno, f"'{what}' expects {need} numbers, got {len(tokens)}")
        out = []
        for tok in tokens[:need]:
            try:
                out.append(float(tok))
            except ValueError:
                fail(lineno, f"bad number '{tok}' in '{what}' statement (expected {need} numbers)")
            if not math.isfinite(out[-1]):
                fail(lineno, f"number '{tok}' in '{what}' statement is not finite (NaN or infinite)")
        return out

    def index(tok, defined, what, lineno, corner):
        try:
            i = int(tok)
        except ValueError:
            fail(lineno, f"bad {what} index '{tok}' in face corner '{corner}' (expected an integer)")
        if i == 0:
            fail(lineno, f"{what} index 0 in face corner '{corner}' (OBJ indices start at 1)")
        if abs(i) > _MAX_INDEX:
            fail(lineno, f"{what} index {i} in face corner '{corner}' is out of range (a mesh holds at "
                         f"most {_MAX_INDEX} vertices)")
        if i < 0:
            r = defined + i
            if r < 0:
                fail(lineno, f"relative {what} index {i} in face corner '{corner}' is out of range "
                             f"(only {defined} defined so far)")
            return r
        return i - 1  # forward references are checked once everything is defined

    for lineno, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0]
        tokens = line.split()
        if not tokens:
            continue
        kw = tokens[0]
        if kw == "v":
            pos.append(numbers(tokens[1:], 3, "v", lineno))
        elif kw == "vt":
            tex.append(numbers(tokens[1:], 2, "vt", lineno))
        elif kw == "vn":
            nor.append(numbers(tokens[1:], 3, "vn", lineno))
        elif kw == "f":
            corners = tokens[1:]
            if len(corners) < 3:
                fail(lineno, f"face has {len(corners)} vertices (expected at least 3)")
            for c in corners:
                parts = c.split("/")
                if len(parts) > 3 or parts[0] == "":
                    fail(lineno, f"bad face corner '{c}' (expected v, v/vt, v//vn or v/vt/vn)")
                v.append(index(parts[0], len(pos), "vertex", lineno, c))
                t.append(index(parts[1], len(tex), "texture coordinate", lineno, c)
                         if len(parts) > 1 and parts[1] != "" else -1)
                n.append(index(parts[2], len(nor), "normal", lineno, c)
                         if len(parts) > 2 and parts[2] != "" else -1)
            counts.append(len(corners))
            face_lines.append(lineno)
        # Everything else (o, g, s, usemtl, mtllib, l, vp, ...) does not affect the geometry.

    va, ta, na = (np.asarray(x, np.int64) for x in (v, t, n))
    ca = np.asarray(counts, np.int64)
    corner_line = np.repeat(np.asarray(face_lines, np.int64), ca)
    for arr, total, what in ((va, len(pos), "vertex"), (ta, len(tex), "texture coordinate"),
                             (na, len(nor), "normal")):
        bad = np.nonzero(arr >= total)[0]
        if bad.size:
            k = bad[0]
            fail(int(corner_line[k]), f"{what} index {arr[k] + 1} is out of range "
                                      f"(the file defines {total})")

    return _Parsed(
        np.asarray(pos, np.float64).reshape(-1, 3),
        np.asarray(tex, np.float64).reshape(-1, 2),
        np.asarray(nor, np.float64).reshape(-1, 3),
        va, ta, na, ca,
    )


# --------------------------------------------------------------------------------------------------
# Triangulation and de-indexing


def _build(p: _Parsed) -> MeshData:
    counts = p.counts
    ntri_per = counts - 2
    ntri = int(ntri_per.sum())
    first_corner = np.cumsum(counts) - counts
    poly = np.repeat(np.arange(counts.size), ntri_per)
    # j runs 1..k-2 within each polygon: fan triangle (0, j, j+1).
    j = np.arange(ntri) - np.repeat(np.cumsum(ntri_per) - ntri_per, ntri_per) + 1
    base = first_corner[poly]
    tc = np.stack([base, base + j, base + j + 1], axis=1).reshape(-1)  # corner ref per triangle corner
    tri_of = np.repeat(np.arange(ntri), 3)

    kv = p.v[tc]
    kt = p.t[tc]
    kn = p.n[tc]
    any_t = bool(np.any(kt >= 0))
    any_n = bool(np.any(kn >= 0))
    missing_n = (kn < 0) if any_n else np.zeros(kn.shape, bool)
    if any_n and np.any(missing_n):
        # A corner without vn takes its triangle's face normal, so it must not be shared across triangles.
        kn = np.where(missing_n, -2 - tri_of, kn)

    # One int64 key per (v, vt, vn) when the ranges allow it; sorting one column is much faster.
    a = kv
    bt = kt + 1
    cn = kn + ntri + 2
    B = len(p.uvs) + 1
    C = len(p.normals) + ntri + 2
    if len(p.positions) * B * C < 2**62:
        key = (a * B + bt) * C + cn
        _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    else:
        _, first, inverse = np.unique(np.stack([a, bt, cn], axis=1), axis=0,
                                      return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    order = np.argsort(first, kind="stable")  # Nori numbers vertices in order of first use
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    src = first[order]  # a triangle-corner slot representing each output vertex

    positions = p.positions[kv[src]]
    faces = rank[inverse].reshape(-1, 3)

    normals = None
    if any_n:
        normals = np.zeros((src.size, 3), np.float64)
        has = ~missing_n[src]
        normals[has] = p.normals[kn[src[has]]]
        if not np.all(has):
            tmp = MeshData(positions, None, None, faces)
            fn = tmp.face_normals()
            normals[~has] = fn[tri_of[src[~has]]]

    uvs = None
    if any_t:
        uvs = np.zeros((src.size, 2), np.float64)
        has = kt[src] >= 0
        uvs[has] = p.uvs[kt[src[has]]]

    return MeshData(positions=positions, normals=normals, uvs=uvs, faces=faces)
