"""XML file -> Scene object (parse, then instantiate the plugins)."""
from __future__ import annotations

from pathlib import Path

from .errors import SceneError, SourceLocation
from .scene.checks import check_mesh_files, warn_if_unlit
from .scene.registry import create
from .scene.xmlparser import parse_file


def load_scene(path, nori_dialect: str | None = None, **defines):
    """Load a Nori or Mitsuba 3 XML scene (a root ``<scene version="...">`` is Mitsuba's); `defines` replace `$name` in attribute values (like `-D name=value`).
    `nori_dialect` is "upstream" (default), "eth" or "eth2023" (see clrender.scene.dialect)."""
    from . import plugins  # noqa: F401  (registers every plugin)

    path = Path(path)
    spec = parse_file(str(path), {k: str(v) for k, v in defines.items()}, nori_dialect=nori_dialect)
    if spec.tag != "scene":
        raise SceneError(f"expected a <scene> file, found <{spec.tag}> (use `clrender test` for test files)",
                         SourceLocation(str(path), spec.location.line, spec.location.col))
    try:
        if spec.format == "mitsuba":
            from .scene.mitsuba_xml import leave_out_unbuildable_unused

            leave_out_unbuildable_unused(spec)
        check_mesh_files(spec)
        scene = create(spec)
    except SceneError as e:
        if spec.format != "mitsuba":
            raise
        from .scene.mitsuba_xml import with_reader

        raise SceneError(with_reader(e.message), e.location) from None
    warn_if_unlit(scene)
    return scene
