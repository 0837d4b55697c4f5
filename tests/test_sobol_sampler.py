"""The stratified sampler (kernels/rng.h with CLR_SAMPLER_SOBOL: padded, shuffled, Owen-scrambled Sobol points),
run in the kernel: every dimension uniform (chi-square), the first 2^k samples of a pixel a (0,k,2)-net in each
dimension pair (one point per elementary interval), pairs of dimensions independent of each other (chi-square of
their joint histogram), keyed by (seed, pixel, sample) so that passes do not matter, and whole renders that agree
with independent samples while their error falls faster."""
import numpy as np
import pyopencl as cl
import pytest
from scipy import stats

import clrender
from clrender.renderer import Renderer
from clrender.device.program import build_program
from clrender.testing.chi2 import chi2_test

SRC = r"""
#include "rng.h"
/* for each (pixel, sample): `dims` successive next2d draws */
__kernel void draw(__global float2* out, uint seed, uint pixels, uint spp, uint dims, uint first_sample) {
    uint g = get_global_id(0);
    if (g >= pixels * spp) return;
    uint pix = g / spp, s = g % spp;
    Sampler smp;
    sampler_init(&smp, seed, pix, first_sample + s);
    for (uint d = 0u; d < dims; ++d) out[g * dims + d] = next2d(&smp);
}
"""


@pytest.fixture(scope="module")
def draw(ctx, queue):
    prg = build_program(ctx, SRC, defines={"CLR_SAMPLER_SOBOL": 1})
    kernel = cl.Kernel(prg, "draw")

    def run(pixels, spp, dims, seed=3, first_sample=0):
        n = pixels * spp
        out = np.zeros((n * dims, 2), np.float32)
        buf = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, out.nbytes)
        kernel(queue, (-(-n // 64) * 64,), (64,), buf, np.uint32(seed), np.uint32(pixels), np.uint32(spp),
               np.uint32(dims), np.uint32(first_sample))
        cl.enqueue_copy(queue, out, buf)
        queue.finish()
        return out.reshape(pixels, spp, dims, 2)

    return run


def test_every_dimension_is_uniform(draw):
    pts = draw(pixels=2048, spp=16, dims=6)
    for d in range(6):
        for c in range(2):
            x = pts[:, :, d, c].ravel()
            assert 0.0 <= x.min() and x.max() < 1.0
            observed = np.bincount((x * 64).astype(int), minlength=64)
            result = chi2_test(observed, np.full(64, len(x) / 64), n_tests=12)
            assert result.passed, (d, c, result.message)


@pytest.mark.parametrize("k", [4, 6, 8])
def test_each_pixel_is_a_net_in_every_dimension_pair(draw, k):
    """The first 2^k samples of a pixel put exactly one point in every elementary interval of area 2^-k (the
    strata 2^a x 2^(k-a) for every a), in every dimension pair: what makes the error fall faster."""
    n = 2 ** k
    pts = draw(pixels=8, spp=n, dims=5)
    for pix in range(8):
        for d in range(5):
            p = pts[pix, :, d]
            for a in range(k + 1):
                cells = (p[:, 0] * 2 ** a).astype(int) * 2 ** (k - a) + (p[:, 1] * 2 ** (k - a)).astype(int)
                assert np.bincount(cells, minlength=n).max() == 1, (pix, d, a)


def test_dimension_pairs_are_independent_of_each_other(draw):
    """Across pixels, (x of one pair, x of another) fills the unit square uniformly: the padding decorrelates
    them (without the per-dimension shuffle and scramble they would be the same point)."""
    pts = draw(pixels=4096, spp=4, dims=4)
    for a, b in [(0, 1), (1, 3), (0, 2)]:
        for ca, cb in [(0, 0), (1, 0), (0, 1)]:
            x, y = pts[:, :, a, ca].ravel(), pts[:, :, b, cb].ravel()
            observed = np.bincount((x * 16).astype(int) * 16 + (y * 16).astype(int), minlength=256)
            result = chi2_test(observed, np.full(256, len(x) / 256), n_tests=9)
            assert result.passed, ((a, ca), (b, cb), result.message)
            assert abs(stats.pearsonr(x, y)[0]) < 4.5 / np.sqrt(len(x))


def test_samples_are_keyed_not_streamed(draw):
    """Sample s of a pixel is the same point whichever launch draws it (passes split a render freely)."""
    whole = draw(pixels=16, spp=32, dims=3)
    parts = np.concatenate([draw(pixels=16, spp=8, dims=3, first_sample=s) for s in (0, 8, 16, 24)], axis=1)
    np.testing.assert_array_equal(whole, parts)
    assert not np.array_equal(whole, draw(pixels=16, spp=32, dims=3, seed=4)), "the seed must matter"


def _scene(tmp_path, sampler):
    xml = f"""<scene version="3.0.0"><integrator type="path"><integer name="max_depth" value="3"/></integrator>
    <sensor type="perspective"><float name="fov" value="40"/>
      <transform name="to_world"><lookat origin="0, 2, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
      <sampler type="{sampler}"><integer name="sample_count" value="64"/></sampler>
      <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="16"/>
        <rfilter type="box"/></film></sensor>
    <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
      <bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></shape>
    <shape type="sphere"><point name="center" value="0, 0.6, 0"/><float name="radius" value="0.6"/></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="0.8"/><rotate x="1" angle="90"/>
      <translate value="0.8, 2.5, 0.5"/></transform><emitter type="area"><rgb name="radiance" value="6"/></emitter>
    </shape></scene>"""
    path = tmp_path / f"{sampler}.xml"
    path.write_text(xml)
    return clrender.load_scene(path)


def test_renders_agree_with_independent_samples_and_converge_faster(tmp_path):
    """Soft shadows and direct light at 64 spp: the per-pixel error over 12 seeds is smaller with the stratified
    sampler, and both sample the same image (their means over the seeds agree, pixel by pixel)."""
    imgs = {}
    for sampler in ("independent", "ldsampler"):
        scene = _scene(tmp_path, sampler)
        r = Renderer(scene)
        imgs[sampler] = np.stack([r.render(seed=s).image for s in range(12)])
    ind, sob = imgs["independent"], imgs["ldsampler"]
    var_ind, var_sob = ind.var(axis=0, ddof=1), sob.var(axis=0, ddof=1)
    lit = var_ind > 1e-6
    assert np.median(var_sob[lit] / var_ind[lit]) < 0.6, np.median(var_sob[lit] / var_ind[lit])
    z = (ind.mean(0) - sob.mean(0)) / np.sqrt((var_ind + var_sob) / 12 + 1e-12)
    assert abs(z.mean()) < 4 * z.std() / np.sqrt(z.size)                # no bias overall
    assert (np.abs(z) > 4.5).mean() < 0.002, np.abs(z).max()            # nor in single pixels
