"""Reading a mesh file's bytes, refusing anything that is not a regular file.

A device file (/dev/zero, /dev/urandom) or a FIFO named as a mesh would be read until memory runs out, or
block forever; a folder gives an obscure error. Only regular files are meshes.

A missing mesh file NAME may have a note beside it, NAME.missing (a short text file), which the error quotes:
scenes/build.py leaves one where a generated mesh that is not kept in git belongs, saying which command makes it.
"""
from __future__ import annotations

import contextlib
import errno
import os
import stat
import warnings

from clrender.errors import SceneError, SourceLocation


def mesh_file_problem(path: str) -> str | None:
    """Why `path` cannot be a mesh file (a sentence), or None if it is a regular file we may read."""
    try:
        st = os.stat(path)
    except OSError as e:
        note = missing_note(path) if e.errno == errno.ENOENT else None
        return (e.strerror or str(e)) + (f" ({os.path.basename(path)}.missing: {note})" if note else "")
    if stat.S_ISDIR(st.st_mode):
        return "it is a folder, not a file"
    if not stat.S_ISREG(st.st_mode):
        kind = ("a FIFO" if stat.S_ISFIFO(st.st_mode) else "a device file"
                if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode) else "a socket or special file")
        return f"it is {kind}; only regular files are meshes"
    if not os.access(path, os.R_OK):
        return "permission denied"
    return None


def missing_note(path: str) -> str | None:
    """The text of PATH.missing (whitespace folded to single spaces), if it is a small regular file."""
    try:
        with open(path + ".missing", "rb") as f:
            if not stat.S_ISREG(os.fstat(f.fileno()).st_mode):
                return None
            text = f.read(2001).decode("utf-8", errors="replace")
    except OSError:
        return None
    return " ".join(text.split())[:2000] or None


def read_mesh_bytes(path, kind: str, location: SourceLocation | None) -> bytes:
    """The whole file; a SceneError at the scene's `location` if it is not a readable regular file."""
    path = os.fspath(path)
    why = mesh_file_problem(path)
    if why is None:
        try:
            with open(path, "rb") as f:
                return f.read()
        except OSError as e:
            why = e.strerror or str(e)
        except MemoryError:
            why = "not enough memory to read it"
    raise SceneError(f"cannot read {kind} file '{path}': {why}", location)


@contextlib.contextmanager
def numpy_text_errors():
    """np.fromstring(text, sep=" ") at a bad token raises ValueError inside, as numpy 2.5 does: numpy 2.2 (the
    newest for Python 3.10) stops there with a DeprecationWarning instead, which users saw."""
    with warnings.catch_warnings():
        # Only this message: the filter is process-wide while it lasts, and another thread gets numpy 2.5's way too.
        warnings.filterwarnings("error", "string or file could not be read to its end", DeprecationWarning)
        try:
            yield
        except DeprecationWarning as e:
            raise ValueError(str(e).split(";")[0]) from None  # numpy 2.5's words, without "will raise in future"
