"""Errors a user can act on: each names where in which file things went wrong."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SourceLocation:
    """A place in an input file (1-based line and column; 0 when unknown)."""

    file: str
    line: int = 0
    col: int = 0

    def __str__(self) -> str:
        if self.line and self.col:
            return f"{self.file}:{self.line}:{self.col}"
        if self.line:
            return f"{self.file}:{self.line}"
        return self.file


class ClrenderError(Exception):
    """Base of every error clrender reports to a user without a traceback."""


class SceneError(ClrenderError):
    """Bad scene input: malformed XML, unknown plugin, bad property, missing or degenerate mesh."""

    def __init__(self, message: str, location: SourceLocation | None = None):
        self.message = message
        self.location = location
        super().__init__(f"{location}: {message}" if location else message)


def git_lfs_hint(data: bytes) -> str:
    """A clause for a bad-header error on a file that is a Git LFS pointer (a clone or archive of a repository that
    keeps the file in Git LFS holds a three-line text in its place), else ''."""
    if not data.startswith(b"version https://git-lfs."):
        return ""
    return "; this is a Git LFS pointer, not the file: fetch the file itself (e.g. `git lfs pull` in that clone)"


class DeviceError(ClrenderError):
    """No usable OpenCL device, or a kernel failed to build or run."""
