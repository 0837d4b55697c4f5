"""Mitsuba 3's and Nori's ply shape (clrender/shapes/ply.py; the reader's own tests are tests/test_meshes.py): a closed
mesh read from a file, sampled as an area light (a chi-square of the directions against the pdf summed over every
hit, traced) and rendered in a furnace (shared set-up: shape_common.py)."""
import pytest

from .shape_common import check_file_shape, closed_mesh


def write_mesh(path):
    v, f, _, _ = closed_mesh()
    path.write_text(f"ply\nformat ascii 1.0\nelement vertex {len(v)}\nproperty float x\nproperty float y\n"
                    f"property float z\nelement face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n" +
                    "".join(f"{x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in v) +
                    "".join(f"3 {a} {b} {c}\n" for a, b, c in f))


@pytest.mark.plugin("ply", "sampling")
@pytest.mark.plugin("ply", "render")
def test_sampling_and_furnace_render(tmp_path, ctx, queue, kernels):
    write_mesh(tmp_path / "m.ply")
    check_file_shape(tmp_path, ctx, queue, kernels, "ply", "m.ply", seed=2008)
