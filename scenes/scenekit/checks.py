"""Checks of the generated scenes (``build.py --check`` and tests/test_scenes_build.py): every XML is what
clrender reads, and each family's numerical sanity checks (its ``check(out)``: framing, normals, ...)."""
from pathlib import Path

import numpy as np

from .camera import project
from .files import read_obj
from .geometry import normalize, rodrigues, rotation_to, round_vec


def check_xml(path):
    """The file is what clrender reads: its own strict parser (tags, attributes, numbers), every plugin type
    known to clrender's registry, and every referenced file present."""
    from clrender import plugins  # noqa: F401  (registers every plugin)
    from clrender.scene.registry import lookup
    from clrender.scene.xmlparser import parse_file

    path = Path(path)
    spec = parse_file(str(path))
    assert spec.tag == "scene", path
    for s in spec.walk():
        if s.tag != "scene":
            lookup(s.tag, s.type, s.location, s.format)
        if s.props.has("filename"):
            assert Path(s.props.get_string("filename")).is_file(), (path, s.props.raw("filename"))
    return spec


def inside(cam, pts, margin=0.0):
    """Every point is in front of the camera and within its image (give or take ``margin`` pixels)."""
    px, py, z = project(cam, np.array(pts, float))
    return bool(np.all(z > 0) and np.all(px >= -margin) and np.all(px <= cam["width"] + margin)
                and np.all(py >= -margin) and np.all(py <= cam["height"] + margin))


def outward(path, center):
    """A closed OBJ's normals point away from ``center`` and its winding agrees with them."""
    V, N, F = read_obj(path)
    assert np.all(np.einsum("ij,ij->i", N, V - np.array(center)) > 0), path
    fn = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    assert np.all(np.einsum("ij,ij->i", fn, N[F[:, 0]]) > 0), path


def sun_rotation(dvec):
    """The rounded rotation written for a sun takes +z to the direction toward it, above the horizon."""
    axis, angle = rotation_to(dvec)
    z = rodrigues(round_vec(axis), round(angle, 4)) @ np.array([0, 0, 1.0])
    assert np.allclose(z, normalize(dvec), atol=1e-4) and z[1] > 0


def sanity_checks(out, families):
    out = Path(out)
    for xml in sorted(out.rglob("*.xml")):
        check_xml(xml)
    for family in families:
        family.check(out)
    return True
