"""Mitsuba 3's serialized shape (clrender/shapes/serialized.py; the format's reader: clrender/shapes/serializedfile.py):
a closed mesh read from a file, sampled as an area light (a chi-square of the directions against the pdf summed over
every hit, traced) and rendered in a furnace (shared set-up: shape_common.py)."""
import numpy as np
import pytest

from .shape_common import check_file_shape, closed_mesh


def write_mesh(path):
    from clrender.shapes.meshdata import MeshData
    from clrender.shapes.serializedfile import write_serialized

    v, f, _, _ = closed_mesh()
    write_serialized(path, [MeshData(positions=v.astype(np.float32), normals=None, uvs=None, faces=f.astype(np.int32))])


@pytest.mark.plugin("serialized", "sampling")
@pytest.mark.plugin("serialized", "render")
def test_sampling_and_furnace_render(tmp_path, ctx, queue, kernels):
    write_mesh(tmp_path / "m.serialized")
    check_file_shape(tmp_path, ctx, queue, kernels, "serialized", "m.serialized", seed=2009)
