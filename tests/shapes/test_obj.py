"""Mitsuba 3's and Nori's obj shape (clrender/shapes/obj.py; the reader's own tests are tests/test_meshes.py): a closed
mesh read from a file, sampled as an area light (a chi-square of the directions against the pdf summed over every
hit, traced) and rendered in a furnace (shared set-up: shape_common.py)."""
import pytest

from .shape_common import check_file_shape, closed_mesh


def write_mesh(path):
    v, f, _, _ = closed_mesh()
    path.write_text("".join(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in v) +
                    "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f))


@pytest.mark.plugin("obj", "sampling")
@pytest.mark.plugin("obj", "render")
def test_sampling_and_furnace_render(tmp_path, ctx, queue, kernels):
    write_mesh(tmp_path / "m.obj")
    check_file_shape(tmp_path, ctx, queue, kernels, "obj", "m.obj", seed=2007)
