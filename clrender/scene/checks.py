"""Whole-scene checks run by `load_scene`: every mesh file readable (all problems in one error), and a
warning when an integrator that needs light finds none."""
from __future__ import annotations

import logging

from ..errors import SceneError
from .spec import PluginSpec

log = logging.getLogger("clrender")

_FILE_MESHES = ("obj", "ply", "serialized")


def check_mesh_files(root: PluginSpec) -> None:
    """Before any mesh is read: name every mesh file that is missing or not a regular file, at once."""
    from ..shapes.meshfile import mesh_file_problem

    problems = []
    for spec in root.walk():
        if spec.tag not in ("mesh", "shape") or spec.type not in _FILE_MESHES or "filename" not in spec.props:
            continue
        if spec.props.tag("filename") != "string":
            continue  # the plugin reports the wrong kind of property
        path = spec.props.get_string("filename")
        why = mesh_file_problem(path)
        if why is not None:
            problems.append((spec.props.location("filename"), spec.type.upper(), path, why))
    if len(problems) == 1:
        where, kind, path, why = problems[0]
        raise SceneError(f"cannot read {kind} file '{path}': {why}", where)
    if problems:
        lines = "\n".join(f"  {where}: {kind} file '{path}': {why}" for where, kind, path, why in problems)
        raise SceneError(f"{len(problems)} mesh files cannot be read:\n{lines}", root.location)


def warn_if_unlit(scene) -> None:
    """Integrators that only see emitted light render black without one (pbrt-v4 warns too)."""
    if not getattr(scene.integrator, "needs_emitter", False):
        return
    if scene.emitters or any(getattr(s, "emitter", None) is not None for s in scene.shapes):
        return
    # name the integrator and the shape tag as the file spells them (the kernel of Mitsuba's 'path' is another)
    integrator = getattr(getattr(scene.integrator, "spec", None), "type", None) or scene.integrator.kernel
    shape = "shape" if getattr(getattr(scene, "spec", None), "format", "nori") == "mitsuba" else "mesh"
    log.warning("%s: the scene has no emitter, so the '%s' integrator renders a black image; add an "
                "<emitter> (e.g. an area light in a <%s>)", scene.location, integrator, shape)
