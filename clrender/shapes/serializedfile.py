"""Mitsuba's ``.serialized`` mesh files: reading (and writing, for tests and tools).

The layout, from Mitsuba's documentation of its serialized shape plugin (little endian):
- per mesh: uint16 0x041C (format), uint16 version (3 or 4); then a zlib (DEFLATE) stream holding uint32 flags
  (0x1 vertex normals, 0x2 uvs, 0x8 vertex colours, 0x10 face normals, 0x1000 float32, 0x2000 float64), the
  mesh's name as a NUL-terminated UTF-8 string (version 4 only), uint64 vertex count, uint64 triangle count, the
  positions (xyz per vertex), normals, uvs, colours (each only when flagged), and the triangles' vertex indices
  (uint32, or uint64 when there are more than 2^32 - 1 vertices);
- meshes are concatenated; the file ends with the offset of each mesh (uint64 in version 4, uint32 in 3) and
  the uint32 mesh count.
Mitsuba 3 ignores the face-normals flag (only the plugin's ``face_normals`` counts), and so do we; vertex
colours are skipped.
"""
from __future__ import annotations

import struct
import zlib

import numpy as np

from ..errors import SceneError, SourceLocation, git_lfs_hint
from .meshdata import MeshData
from .meshfile import read_mesh_bytes

MAGIC = 0x041C
HAS_NORMALS, HAS_UVS, HAS_COLORS, FACE_NORMALS = 0x1, 0x2, 0x8, 0x10
SINGLE, DOUBLE = 0x1000, 0x2000


def _fail(path, why: str, location) -> SceneError:
    return SceneError(f"bad serialized mesh file '{path}': {why}", location)


def mesh_offsets(data: bytes, version: int, path, location) -> list[int]:
    """Where each mesh of the file starts (from the dictionary at its end)."""
    if len(data) < 8:
        raise _fail(path, "too short for the mesh dictionary at its end", location)
    (count,) = struct.unpack_from("<I", data, len(data) - 4)
    size = 8 if version == 4 else 4
    start = len(data) - 4 - size * count
    if count == 0 or start < 4:
        raise _fail(path, f"its end dictionary claims {count} meshes, which do not fit the file", location)
    return list(struct.unpack_from(f"<{count}{'Q' if size == 8 else 'I'}", data, start))


def load_serialized(path, location: SourceLocation | None = None, shape_index: int = 0) -> MeshData:
    data = read_mesh_bytes(path, "serialized mesh", location)
    if len(data) < 4:
        raise _fail(path, "shorter than its 4-byte header", location)
    magic, version = struct.unpack_from("<HH", data, 0)
    if magic != MAGIC:
        raise _fail(path, f"it starts with 0x{magic:04X}, not the serialized format's 0x{MAGIC:04X}"
                    f"{git_lfs_hint(data)}", location)
    if version not in (3, 4):
        raise _fail(path, f"format version {version}; Mitsuba's readers (and clrender) take 3 and 4", location)
    offset = 0
    if shape_index != 0:
        offsets = mesh_offsets(data, version, path, location)
        if shape_index >= len(offsets):
            raise _fail(path, f"shape_index {shape_index} is out of range: the file holds {len(offsets)} "
                              f"mesh(es), 0..{len(offsets) - 1}", location)
        offset = offsets[shape_index]
        if not 0 <= offset <= len(data) - 4 or struct.unpack_from("<HH", data, offset) != (MAGIC, version):
            raise _fail(path, f"mesh {shape_index} does not start with a header at offset {offset}", location)
    try:
        body = _inflate(data[offset + 4:], version, path, location)
    except zlib.error as e:
        raise _fail(path, f"its compressed stream is corrupt ({e})", location) from None
    return _parse_mesh(body, version, path, location)


#: DEFLATE expands its input at most about 1032-fold
_MAX_RATIO = 1032


def _inflate(stream: bytes, version: int, path, location) -> bytes:
    """The mesh's decompressed data, and no more than its header says it holds: a small file whose stream
    inflates to gigabytes (a zlib bomb) is refused from its counts instead of exhausting the memory."""
    d = zlib.decompressobj()
    head = d.decompress(stream, 1 << 16)  # flags, name, counts (the name is short)
    need = len(head)
    if len(head) >= 4:
        (flags,) = struct.unpack_from("<I", head, 0)
        at = 4 if version == 3 else head.find(b"\0", 4) + 1
        if at > 0 and at + 16 <= len(head):
            nv, nf = struct.unpack_from("<QQ", head, at)
            fsize = 8 if flags & DOUBLE else 4
            per_vertex = 3 + (3 if flags & HAS_NORMALS else 0) + (2 if flags & HAS_UVS else 0) + \
                (3 if flags & HAS_COLORS else 0)
            need = at + 16 + nv * per_vertex * fsize + nf * 3 * (8 if nv > 0xFFFFFFFF else 4)
            if need > _MAX_RATIO * len(stream) + 1024:
                raise _fail(path, f"it claims {nv} vertices and {nf} triangles, more than its {len(stream)} "
                                  f"compressed bytes can hold", location)
    return head + d.decompress(d.unconsumed_tail, max(need - len(head), 1))


def _parse_mesh(body: bytes, version: int, path, location) -> MeshData:
    pos = 0

    def take(n: int, what: str) -> bytes:
        nonlocal pos
        if pos + n > len(body):
            raise _fail(path, f"the mesh data ends inside its {what}", location)
        out = body[pos:pos + n]
        pos += n
        return out

    (flags,) = struct.unpack("<I", take(4, "flags"))
    if version == 4:
        end = body.find(b"\0", pos)
        if end < 0:
            raise _fail(path, "the mesh name is not NUL-terminated", location)
        pos = end + 1
    nv, nf = struct.unpack("<QQ", take(16, "counts"))
    if flags & DOUBLE and flags & SINGLE:
        raise _fail(path, "flags ask for both single and double precision", location)
    ftype = np.dtype("<f8") if flags & DOUBLE else np.dtype("<f4")
    limit = len(body)
    if nv * 3 * ftype.itemsize > limit or nf * 3 * 4 > limit:
        raise _fail(path, f"{nv} vertices and {nf} triangles do not fit its {limit} bytes of data", location)

    def array(dim: int, what: str) -> np.ndarray:
        return np.frombuffer(take(nv * dim * ftype.itemsize, what), ftype).reshape(nv, dim).astype(np.float64)

    positions = array(3, "positions")
    normals = array(3, "normals") if flags & HAS_NORMALS else None
    uvs = array(2, "uvs") if flags & HAS_UVS else None
    if flags & HAS_COLORS:
        array(3, "vertex colours")
    itype = np.dtype("<u8") if nv > 0xFFFFFFFF else np.dtype("<u4")
    faces = np.frombuffer(take(nf * 3 * itype.itemsize, "triangles"), itype).reshape(nf, 3)
    if nf and faces.max() >= nv:
        raise _fail(path, f"a triangle uses vertex {int(faces.max())} of {nv}", location)
    for what, a in (("position", positions), ("normal", normals), ("uv", uvs)):
        if a is not None and not np.all(np.isfinite(a)):
            raise _fail(path, f"a vertex {what} is not finite", location)
    return MeshData(positions=positions, normals=normals, uvs=uvs, faces=faces.astype(np.int64))


def write_serialized(path, meshes, version: int = 4, double: bool = False) -> None:
    """Write ``meshes`` (MeshData, or (name, MeshData)) as one .serialized file."""
    chunks, offsets, at = [], [], 0
    ftype = "<f8" if double else "<f4"
    for item in meshes:
        name, m = item if isinstance(item, tuple) else ("", item)
        flags = (DOUBLE if double else SINGLE) | (HAS_NORMALS if m.normals is not None else 0) | \
            (HAS_UVS if m.uvs is not None else 0)
        body = struct.pack("<I", flags)
        if version == 4:
            body += name.encode() + b"\0"
        body += struct.pack("<QQ", len(m.positions), len(m.faces))
        for a in (m.positions, m.normals, m.uvs):
            if a is not None:
                body += np.ascontiguousarray(a, ftype).tobytes()
        body += np.ascontiguousarray(m.faces, "<u4").tobytes()
        chunk = struct.pack("<HH", MAGIC, version) + zlib.compress(body)
        offsets.append(at)
        chunks.append(chunk)
        at += len(chunk)
    tail = struct.pack(f"<{len(offsets)}{'Q' if version == 4 else 'I'}", *offsets) + struct.pack("<I", len(offsets))
    with open(path, "wb") as f:
        f.write(b"".join(chunks) + tail)
