"""Mitsuba 3's bitmap texture (clrender/textures/bitmap.py, kernels/textures/bitmap.h): its uv gradient, bumpmap's
slope, on the device and on the host against Mitsuba 3.9.1's eval_1_grad (tests/mitsuba/bsdf_values/perturbed.json,
written by make_perturbed_values.py there), and a rendered plane that shows the image at its uv. Its lookups for
every filter, wrap mode and image format are still tested in tests/test_mitsuba_textures.py."""
import numpy as np
import pytest

from bsdfs.perturbed_common import DATA, spec
from clrender.scene.registry import create
from clrender.testing.plugin_checks import check_texture_render
from clrender.textures.texture import TextureTable

GRAD_SRC = r"""
#include "texture.h"
#include "textures/bitmap.h"
__kernel void grad(__global const Texture* textures, uint row, __global const float2* uv, __global float2* out) {
    uint i = get_global_id(0);
    out[i] = bitmap_grad(textures + row, uv[i]);
}
"""


@pytest.mark.plugin("bitmap", "eval")
@pytest.mark.parametrize("name", sorted(DATA["gradients"]))
def test_bitmap_gradient_is_mitsubas(ctx, queue, name):
    """bumpmap's slope: the bitmap's uv gradient on the device (bitmap_grad) and on the host (Bitmap.eval_grad) as
    Mitsuba's eval_1_grad gives it (of the luminance, through to_uv, every wrap mode; none for `nearest`)."""
    import pyopencl as cl

    from clrender.device.program import build_program

    case = DATA["gradients"][name]
    tex = create(spec(case["dict"], "texture")).float_view()
    uv, ref = np.array(case["uv"]), np.array(case["grad"])
    np.testing.assert_allclose(tex.eval_grad(uv), ref, rtol=1e-4, atol=1e-4 * np.abs(ref).max())
    table = TextureTable()
    row = table.add(tex)
    mf = cl.mem_flags
    d_tex = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=table.array())
    d_uv = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=uv.astype(np.float32))
    out = np.empty((len(uv), 2), np.float32)
    d_out = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
    cl.Kernel(build_program(ctx, GRAD_SRC), "grad")(queue, (len(uv),), None, d_tex, np.uint32(row), d_uv, d_out)
    cl.enqueue_copy(queue, out, d_out)
    queue.finish()
    np.testing.assert_allclose(out, ref, rtol=1e-3, atol=1e-3 * np.abs(ref).max())
    if name == "nearest":
        assert not ref.any()
    else:
        assert np.abs(ref).max() > 0.5


@pytest.mark.plugin("bitmap", "render")
def test_furnace_render(tmp_path):
    """A diffuse plane with a bitmap reflectance (a 5 x 7 sRGB PNG, bilinear) in a constant environment of radiance 1
    shows the image's value at its uv."""
    from PIL import Image

    img = (np.random.default_rng(4).random((5, 7, 3)) * 255).astype(np.uint8)
    Image.fromarray(img).save(tmp_path / "t.png")
    check_texture_render(tmp_path, f'<texture type="bitmap" name="reflectance"><string name="filename" '
                                   f'value="{tmp_path / "t.png"}"/></texture>', "mitsuba")
