"""The `clrender` command (a thin wrapper over the Python API): `main` parses and runs one command.

Modules: app (the parser; render, devices, bench; exit statuses), options (what several commands share),
distributed (render --cluster / --sample-range, merge), tests (test, warptest).
"""
from .app import main

__all__ = ["main"]
