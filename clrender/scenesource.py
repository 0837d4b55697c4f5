"""Where a scene comes from (XML file, `-D` defines, Nori dialect) and its content hash.

The hash covers the XML bytes, the defines, the dialect and the bytes of every file the scene names
(meshes, textures), never their paths: the same scene checked out on two machines hashes the same, and an
edited mesh changes it. Farm parts carry it so `clrender merge` can refuse parts of different scenes, and
cluster workers that read the scene from a shared filesystem check it against the client's.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path

from .errors import SceneError

from .scene.dialect import DEFAULT as DEFAULT_DIALECT  # noqa: E402
_HASH_VERSION = b"clrender-scene-hash-1\0"


@dataclass(frozen=True)
class SceneSource:
    path: str
    defines: dict = field(default_factory=dict)
    dialect: str = DEFAULT_DIALECT

    def load(self):
        """The Scene, loaded exactly as the client loaded it (same defines, same dialect)."""
        from .loader import load_scene

        # always explicit: a worker's own $CLRENDER_NORI_DIALECT must not change what the client chose
        return load_scene(self.path, nori_dialect=self.dialect, **self.defines)

    def referenced_files(self) -> list[str]:
        """Every file the scene names (``<string name="filename">``, and files a Mitsuba scene includes),
        resolved, in document order."""
        from .scene.xmlparser import parse_file

        spec = parse_file(self.path, {k: str(v) for k, v in self.defines.items()})
        out = []
        for s in spec.walk():
            # a Mitsuba <include>d file: its objects are located in it
            where = s.location.file if s.location is not None else None
            if where and where != self.path and not where.startswith("<") and where not in out:
                out.append(where)
            if "filename" in s.props and s.props.tag("filename") == "string":
                out.append(s.props.peek("filename"))
        return out

    def content_hash(self) -> str:
        """Hex sha256 (first 32 digits) of what the image depends on; see the module docstring."""
        h = hashlib.sha256(_HASH_VERSION)
        h.update(self.dialect.encode() + b"\0")
        for k in sorted(self.defines):
            h.update(f"{k}={self.defines[k]}".encode() + b"\0")
        h.update(_file_digest(self.path))
        for name in self.referenced_files():
            try:
                h.update(_file_digest(name))
            except SceneError:
                h.update(b"missing\0")  # loading reports it with its line; the hash must not fail first
        return h.hexdigest()[:32]


def _file_digest(path) -> bytes:
    h = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            for chunk in iter(lambda: f.read(1 << 20), b""):
                h.update(chunk)
    except OSError as exc:
        raise SceneError(f"cannot read '{path}': {exc.strerror or exc}") from None
    return h.digest()


def packed_hash(buffers, integrator: str, width: int, height: int) -> str:
    """Hash of a packed scene (for scenes handed over as objects, whose source may be unknown)."""
    import numpy as np

    h = hashlib.sha256(_HASH_VERSION + b"packed\0")
    h.update(f"{integrator}:{width}x{height}:{buffers.bvh_width}:{buffers.sampler}".encode())
    for a in buffers.scene_arrays() + [buffers.camera, buffers.filter_cdf]:
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()[:32]


def resolve(path) -> str:
    return str(Path(path).resolve())
