"""Stanford PLY loading (ASCII and binary) into `MeshData`.

ASCII files are decoded by trimesh's PLY reader; we take its raw element arrays (not the Trimesh object,
which would reorder quads and may recompute normals). Binary files are read here, straight into numpy
record arrays: importing trimesh takes 0.75 s (it imports scipy.spatial), more than reading a 1 M-triangle
file. Either way we apply our own semantics:
vertex normals `nx ny nz` are kept exactly as stored, uvs come from `u v`, `s t` or `texture_u
texture_v`, and polygons are fan-triangulated (0,1,2), (0,2,3), ... in file order, like OBJ faces.

A binary element whose lists all have the length of its first record's (triangles, or quads) is one
frombuffer; one with lists of different lengths is walked record by record.
"""
from __future__ import annotations

import os
import re

import numpy as np

from clrender.errors import SceneError, SourceLocation, git_lfs_hint
from clrender.shapes.meshdata import MeshData
from clrender.shapes.meshfile import numpy_text_errors, read_mesh_bytes

__all__ = ["load_ply"]

_UV_NAMES = (("u", "v"), ("s", "t"), ("texture_u", "texture_v"), ("texture_s", "texture_t"))
_INDEX_NAMES = ("vertex_indices", "vertex_index")


def load_ply(path, location: SourceLocation | None = None) -> MeshData:
    """Load a PLY mesh (object space). Errors name the PLY file, or `location` if it cannot be read."""
    path = os.fspath(path)
    data = read_mesh_bytes(path, "PLY", location)
    here = SourceLocation(path)
    if not data.startswith(b"ply"):
        raise SceneError(f"not a PLY file (expected 'ply' on the first line){git_lfs_hint(data)}", here)
    _check_header(data, path)

    try:
        if re.search(rb"^format\s+ascii\b", data[:data.find(b"end_header")], re.M):
            vertex, polygons, face = _read_with_trimesh(data)
        else:
            vertex, polygons, face = _read_binary(data, here)
    except SceneError:
        raise
    except Exception as e:  # trimesh raises assorted types for malformed files
        raise SceneError(f"cannot parse PLY file: {type(e).__name__}: {e}", here) from None

    try:
        return _mesh_from(vertex, polygons, here, face)
    except (ValueError, TypeError, IndexError, OverflowError) as e:
        # e.g. an ASCII line with fewer numbers than the header promises: trimesh hands back ragged rows
        raise SceneError(f"PLY data do not match the header ({type(e).__name__}: {e})", here) from None


#: Mitsuba 3.9.1's attribute name postfixes (src/shapes/ply.h, find_other_fields): a group's fields run x y z w, r g b a,
#: 0 1 2 3 or 1 2 3 4, its postfix scheme being the column its first field's postfix is in
_POSTFIXES = ("xr01", "yg12", "zb23", "wa34")


def _attributes(element, kind: str, reserved: set, count: int, here: SourceLocation) -> dict:
    """Mitsuba 3.9.1's mesh attributes of a PLY element (``kind`` "vertex_" or "face_"): `r g b [a]` (or `red green
    blue [alpha]`) make ``<kind>color``; other fields ``<prefix>_<postfix>``, one or three in a row with one
    prefix and a postfix scheme of _POSTFIXES, make ``<kind><prefix>`` (``<kind><prefix>_color`` for r g b);
    integer fields are normalised to [0, 1] and sRGB-decoded, as Mitsuba's PLY reader flags them. Fields that
    follow none of this are passed over (Mitsuba warns)."""
    from ..textures.imagefile import srgb_to_linear

    if element is None or count == 0:
        return {}
    names = [n for n in _field_names(element) if not n.endswith(" count")]

    def column(n):
        a = np.asarray(element[n])
        if a.ndim != 1 or a.shape[0] != count:
            return None
        if a.dtype.kind in "iu":   # Mitsuba's Normalized | Gamma integer fields
            return srgb_to_linear(a.astype(np.float64) / np.iinfo(a.dtype).max)
        return a.astype(np.float64)

    out = {}
    rename = {"red": "r", "green": "g", "blue": "b", "alpha": "a"}
    plain = {rename.get(n, n): n for n in names if n in ("r", "g", "b", "a", "red", "green", "blue", "alpha")}
    if {"r", "g", "b"} <= set(plain):
        cols = [column(plain[c]) for c in "rgb"]
        if all(c is not None for c in cols):
            out[kind + "color"] = np.stack(cols, axis=1)
    i = 0
    rest = [n for n in names if n not in reserved and n not in plain.values()]
    while i < len(rest):
        prefix, _, post = rest[i].rpartition("_")
        if not prefix or len(post) != 1 or post not in _POSTFIXES[0]:
            i += 1
            continue
        scheme = _POSTFIXES[0].index(post)
        group = [rest[i]]
        while (i + len(group) < len(rest) and len(group) < 4
               and rest[i + len(group)] == f"{prefix}_{_POSTFIXES[len(group)][scheme]}"):
            group.append(rest[i + len(group)])
        i += len(group)
        cols = [column(n) for n in group]
        if len(group) in (1, 3) and all(c is not None for c in cols):
            out[kind + prefix + ("_color" if scheme == 1 else "")] = np.stack(cols, axis=1)
    return out


def _mesh_from(vertex, polygons, here: SourceLocation, face=None) -> MeshData:
    names = set(_field_names(vertex))
    if not {"x", "y", "z"} <= names:
        raise SceneError("PLY vertex element lacks x/y/z properties", here)
    positions = np.column_stack([np.asarray(vertex[k], np.float64) for k in "xyz"])
    normals = None
    if {"nx", "ny", "nz"} <= names:
        normals = np.column_stack([np.asarray(vertex[k], np.float64) for k in ("nx", "ny", "nz")])
    uvs = None
    for a, b in _UV_NAMES:
        if a in names and b in names:
            uvs = np.column_stack([np.asarray(vertex[a], np.float64), np.asarray(vertex[b], np.float64)])
            break

    for what, arr in (("coordinate", positions), ("normal", normals), ("texture coordinate", uvs)):
        if arr is not None and not np.isfinite(arr).all():
            k = int(np.flatnonzero(~np.isfinite(arr).all(axis=1))[0])
            raise SceneError(f"PLY vertex {k} has a non-finite {what} ({', '.join(map(str, arr[k]))})", here)

    faces = _fan(polygons, here)
    if faces.shape[0] == 0:
        raise SceneError("PLY file contains no faces", here)
    if faces.min() < 0 or faces.max() >= positions.shape[0]:
        raise SceneError(f"PLY face index out of range (the file has {positions.shape[0]} vertices)", here)
    uv_names = {n for pair in _UV_NAMES for n in pair}
    attributes = _attributes(vertex, "vertex_", {"x", "y", "z", "nx", "ny", "nz"} | uv_names, len(positions), here)
    n_polygons = len(polygons)
    face_attributes = _attributes(face, "face_", set(_INDEX_NAMES), n_polygons, here) if n_polygons else {}
    if face_attributes:
        # a polygon's attribute goes to each triangle of its fan (_fan keeps polygons in order)
        sizes = np.array([len(np.asarray(q).reshape(-1)) for q in polygons]) if isinstance(polygons, list) \
            else np.full(n_polygons, np.asarray(polygons).shape[1])
        repeat = np.maximum(sizes - 2, 0)
        attributes.update({k: np.repeat(v, repeat, axis=0) for k, v in face_attributes.items()})
    return MeshData(positions=positions, normals=normals, uvs=uvs, faces=faces, attributes=attributes)


def _check_header(data: bytes, path: str) -> None:
    """Check the header and that the body can hold what it declares, before anything is allocated.

    A truncated file, or a header claiming billions of vertices, is reported here with the header line,
    instead of failing inside a reader (or allocating what the header claims)."""
    end = data.find(b"end_header")
    if end < 0:
        raise SceneError("PLY header has no 'end_header' line (truncated or not a PLY file)", SourceLocation(path))
    nl = data.find(b"\n", end)
    body = len(data) - (nl + 1) if nl >= 0 else 0
    fmt = None
    elements: list[tuple[str, int, int, int]] = []  # name, count, line, bytes per record at least
    lists: list[list[bool]] = []  # per element, per property: is it a list
    header_lines = data[:end].count(b"\n") + 1  # the end_header line's number
    for lineno, raw in enumerate(data[:end].decode("ascii", "replace").splitlines(), start=1):
        tok = raw.split()
        here = SourceLocation(path, lineno)
        if not tok or tok[0] in ("ply", "comment", "obj_info"):
            continue
        if tok[0] == "format":
            if len(tok) < 2 or tok[1] not in ("ascii", "binary_little_endian", "binary_big_endian"):
                raise SceneError(f"unknown PLY format line '{raw.strip()}' (expected ascii, "
                                 "binary_little_endian or binary_big_endian)", here)
            fmt = tok[1]
        elif tok[0] == "element":
            if len(tok) != 3 or not tok[2].isdigit():
                raise SceneError(f"bad PLY element line '{raw.strip()}' (expected 'element NAME COUNT')", here)
            elements.append((tok[1], int(tok[2]), lineno, 0))
            lists.append([])
        elif tok[0] == "property":
            if not elements:
                raise SceneError("PLY property before any element", here)
            if len(tok) == 5 and tok[1] == "list" and tok[2] in _PLY_TYPES and tok[3] in _PLY_TYPES:
                if tok[4] in _INDEX_NAMES and _PLY_TYPES[tok[3]][0] == "f":
                    # a fractional index would be truncated to another vertex without a word
                    raise SceneError(f"PLY face index list '{tok[4]}' has type {tok[3]}; vertex indices must be "
                                     "integers (e.g. int or uint)", here)
                size = np.dtype(_PLY_TYPES[tok[2]]).itemsize  # an empty list is only its length
            elif len(tok) == 3 and tok[1] in _PLY_TYPES:
                size = np.dtype(_PLY_TYPES[tok[1]]).itemsize
            else:
                raise SceneError(f"bad PLY property line '{raw.strip()}' (expected 'property TYPE NAME' or "
                                 f"'property list COUNT_TYPE INDEX_TYPE NAME'; types: "
                                 f"{', '.join(_PLY_TYPES)})", here)
            name, count, line, per = elements[-1]
            elements[-1] = (name, count, line, per + size)
            lists[-1].append(tok[1] == "list")
        else:
            raise SceneError(f"unknown PLY header line '{raw.strip()}'", here)
    if fmt is None:
        raise SceneError("PLY header has no 'format' line", SourceLocation(path))
    if fmt == "ascii":
        lines = data.count(b"\n", nl + 1) + 1 if nl >= 0 else 0
        need = sum(count for _, count, _, _ in elements)
        if need > lines:
            raise SceneError(f"the PLY header declares {need} records but the file has only {lines} lines "
                             "after the header (truncated, or a wrong element count)", SourceLocation(path))
        _check_ascii_records(data[nl + 1:], elements, lists, header_lines, path)
        return
    offset = 0
    for name, count, line, per in elements:
        offset += count * per
        if offset > body:
            raise SceneError(f"PLY header declares {count} '{name}' records, at least {count * per} bytes, but "
                             f"the file has only {body} bytes after the header (truncated, or a wrong "
                             f"element count)", SourceLocation(path, line))


def _check_ascii_records(body: bytes, elements, lists, header_lines: int, path: str) -> None:
    """Each ASCII record (one a line) must hold exactly the numbers its properties and list lengths call for:
    the line-based reader would otherwise drop extra numbers, or read a list shorter than its length says,
    without a word."""
    lines = body.split(b"\n")
    at = 0
    for (name, count, _, _), is_list in zip(elements, lists):
        n_props = len(is_list)
        for k in range(at, at + count):
            tok = lines[k].split()
            need, want = 0, None
            for lst in is_list:
                if lst:
                    try:
                        need += 1 + int(tok[need])
                    except (IndexError, ValueError):
                        want = f"a list length as number {need + 1}"
                        break
                else:
                    need += 1
            if want is not None or need != len(tok):
                props = f"{n_props} propert{'y' if n_props == 1 else 'ies'}"
                want = want or f"{need} ({props}{', each list as long as its length says' if any(is_list) else ''})"
                raise SceneError(f"PLY '{name}' record {k - at} holds {len(tok)} numbers where the header calls "
                                 f"for {want}{_COUNTS_HINT}", SourceLocation(path, header_lines + 1 + k))
        at += count


def _field_names(element) -> list[str]:
    if isinstance(element, dict):
        return list(element.keys())
    return list(element.dtype.names or ())


def _read_with_trimesh(data: bytes):
    """(vertex fields, list of polygon index arrays or an (F, k) array) from trimesh's raw elements (ASCII)."""
    import io

    from trimesh.exchange import ply as tply

    with numpy_text_errors():  # else numpy 2.2 warns at a bad number and trimesh hands back ragged rows
        kwargs = tply.load_ply(io.BytesIO(data), fix_texture=False, skip_materials=True)
    elements = kwargs["metadata"]["_ply_raw"]
    if "vertex" not in elements or elements["vertex"].get("data") is None:
        raise ValueError("no vertex element")
    vertex = elements["vertex"]["data"]
    face = elements.get("face", {}).get("data")
    if face is None:
        return vertex, np.zeros((0, 3), np.int64), None
    for name in _INDEX_NAMES:
        if name in _field_names(face):
            lists = face[name]
            break
    else:
        raise ValueError("face element has no vertex_indices list")
    if isinstance(face, np.ndarray):
        lists = lists["f1"]  # binary: ('f0' = list length, 'f1' = the indices)
    return vertex, lists, face


#: a header whose vertex count is smaller than the data makes the reader take vertex data for faces
_COUNTS_HINT = " (or the header's element counts do not match the data)"


def _fan(polygons, here: SourceLocation) -> np.ndarray:
    arr = np.asarray(polygons) if not isinstance(polygons, list) else None
    if arr is not None and arr.dtype != object and arr.ndim == 2:
        k = arr.shape[1]
        if k < 3:
            raise SceneError(f"PLY face has {k} vertices (expected at least 3){_COUNTS_HINT}", here)
        j = np.arange(1, k - 1)
        tri = np.stack([np.broadcast_to(arr[:, :1], (arr.shape[0], k - 2)), arr[:, j], arr[:, j + 1]],
                       axis=2)
        return tri.reshape(-1, 3).astype(np.int64)
    out = []
    for poly in polygons:
        poly = np.asarray(poly, np.int64).reshape(-1)
        if poly.size < 3:
            raise SceneError(f"PLY face has {poly.size} vertices (expected at least 3){_COUNTS_HINT}", here)
        j = np.arange(1, poly.size - 1)
        out.append(np.stack([np.full(j.size, poly[0]), poly[j], poly[j + 1]], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 3), np.int64)


_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def _read_binary(data: bytes, here: SourceLocation):
    """(vertex records, polygons: an (F, k) array or a list of index arrays) of a binary PLY (header checked
    by _check_header)."""
    end = data.find(b"end_header")
    if end < 0:
        raise SceneError("PLY header has no end_header", here)
    body_start = data.index(b"\n", end) + 1
    endian = "<"
    elements: list[tuple[str, int, list]] = []
    for raw in data[:end].decode("ascii", "replace").splitlines():
        tok = raw.split()
        if not tok:
            continue
        if tok[0] == "format":
            endian = ">" if "big" in tok[1] else "<"
        elif tok[0] == "element":
            elements.append((tok[1], int(tok[2]), []))
        elif tok[0] == "property" and elements:
            if tok[1] == "list":
                elements[-1][2].append((tok[4], _PLY_TYPES[tok[2]], _PLY_TYPES[tok[3]]))
            else:
                elements[-1][2].append((tok[2], _PLY_TYPES[tok[1]], None))
    buf = memoryview(data)
    off = body_start
    vertex = face = None
    polygons: list | np.ndarray = []
    for name, count, props in elements:
        rec, off = _uniform_records(buf, off, count, props, endian, name, here)
        if rec is None:   # lists of different lengths: {list property: [index arrays]}
            rec, off = _walk_records(buf, off, count, props, endian, name, here)
        elif name == "vertex":
            vertex = rec
        if name == "face":
            polygons = next((rec[i] for i in _INDEX_NAMES if i in _field_names(rec)), polygons)
            face = rec if isinstance(rec, np.ndarray) else None   # other properties: uniform records only
    if vertex is None:
        raise SceneError("PLY file has no vertex element", here)
    return vertex, polygons, face


def _uniform_records(buf, off: int, count: int, props, endian: str, name: str, here: SourceLocation):
    """(records, next offset) of an element whose every list has the length its first record's has, read
    as one record array; (None, off) when a list's length differs (or a list is empty), for _walk_records."""
    fields = []
    at = off
    for pname, t1, t2 in props:
        if t2 is None:
            fields.append((pname, endian + t1))
            at += np.dtype(t1).itemsize
            continue
        if count == 0:
            return None, off
        if at + np.dtype(t1).itemsize > len(buf):
            raise SceneError(f"PLY file ends inside '{name}' record (truncated)", here)
        n = int(np.frombuffer(buf, endian + t1, 1, at)[0])
        if n <= 0:
            return None, off
        fields += [(pname + " count", endian + t1), (pname, endian + t2, (n,))]
        at += np.dtype(t1).itemsize + np.dtype(t2).itemsize * n
    dt = np.dtype(fields)
    if off + dt.itemsize * count > len(buf):
        if any(p[2] is not None for p in props):
            return None, off    # lists shorter later on, or a truncated file: the walk tells which
        raise SceneError(f"PLY file ends inside '{name}' records (truncated)", here)
    rec = np.frombuffer(buf, dtype=dt, count=count, offset=off)
    for pname, _, t2 in props:
        if t2 is not None and not np.all(rec[pname + " count"] == rec[pname].shape[1]):
            return None, off
    return rec, off + dt.itemsize * count


def _walk_records(buf, off: int, count: int, props, endian: str, name: str, here: SourceLocation):
    """({list property: [index arrays]}, next offset): an element whose lists vary in length, record by record."""
    lists: dict[str, list] = {p[0]: [] for p in props if p[2] is not None}
    for _ in range(count):
        for pname, t1, t2 in props:
            if t2 is None:
                off += np.dtype(t1).itemsize
                continue
            if off + np.dtype(t1).itemsize > len(buf):
                raise SceneError(f"PLY file ends inside '{name}' record (truncated)", here)
            n = int(np.frombuffer(buf, endian + t1, 1, off)[0])
            off += np.dtype(t1).itemsize
            if n < 0 or off + np.dtype(t2).itemsize * n > len(buf):
                raise SceneError(f"PLY '{name}' list of {n} entries runs past the end of the file "
                                 "(truncated or corrupt)", here)
            lists[pname].append(np.frombuffer(buf, endian + t2, n, off))
            off += np.dtype(t2).itemsize * n
    return lists, off
