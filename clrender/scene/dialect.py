"""The two dialects of Nori's XML format, which differ in how a file's numbers become an image.

- ``upstream``: wjakob/nori (the EPFL course base, the reference images on Nori's website). Camera +x
  appears on the image's left; ``rotate`` axes are normalised.
- ``eth``: the ETH Zürich CG course base and the Dartmouth 2015 fork. Camera +x appears on the image's
  right; ``rotate`` axes are passed to Eigen's AngleAxis as written (not normalised).

A scene file does not say which one it is written for, so the user chooses: an explicit argument
(``--nori-dialect``, ``load_scene(..., nori_dialect=)``), else the environment variable
``CLRENDER_NORI_DIALECT``, else ``upstream``.
"""
from __future__ import annotations

import os

from ..errors import ClrenderError

DIALECTS = ("upstream", "eth")
DEFAULT = "upstream"
ENV_VAR = "CLRENDER_NORI_DIALECT"


def resolve(dialect: str | None = None) -> str:
    """The dialect to use: ``dialect`` if given, else $CLRENDER_NORI_DIALECT, else ``upstream``."""
    source = "nori_dialect"
    if dialect is None or dialect == "":
        dialect = os.environ.get(ENV_VAR, "")
        source = f"${ENV_VAR}"
    if dialect == "":
        return DEFAULT
    d = str(dialect).strip().lower()
    if d not in DIALECTS:
        raise ClrenderError(f"{source}: unknown Nori dialect '{dialect}'; choose one of {', '.join(DIALECTS)} "
                            f"(upstream = wjakob/nori and EPFL; eth = ETH Zürich and Dartmouth forks)")
    return d


def mirrors_camera_x(dialect: str) -> bool:
    """True where camera +x appears on the image's left (upstream Nori, like Mitsuba)."""
    return dialect == "upstream"


def normalizes_rotate_axis(dialect: str) -> bool:
    return dialect == "upstream"
