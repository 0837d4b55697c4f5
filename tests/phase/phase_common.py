"""Phase functions on the device, in bulk: samples (direction, weight, pdf) and densities of a packed Phase row,
for the chi-square tests of tests/phase/ (the program holds every phase plugin; random numbers are kernels/rng.h's
Sampler keyed by (seed, sample index, 0), as clrender/testing/kernels.py's batches)."""
import numpy as np

from clrender.device.program import MIN_GENERIC_GLOBAL, build_program
from clrender.testing.chi2 import bin_directions, chi2_test, expected_from_grid, refined_direction_grid

SOURCE = r'''
#include "rng.h"
#include "gen/phase_dispatch.h"
__kernel void phase_sample_batch(__global const Phase* row, float4 wi, uint n, uint seed, __global float4* out,
                                 __global float* pdf) {
    uint i = get_global_id(0);
    if (i >= n) return;
    Sampler s;
    sampler_init(&s, seed, i, 0u);
    PhaseQuery q;
    q.wi = vxyz(wi);
    float w = phase_sample(row, &q, next2d(&s));
    out[i] = vf4(q.wo, w);
    pdf[i] = q.pdf;
}
__kernel void phase_eval_batch(__global const Phase* row, float4 wi, uint n, __global const float4* wo,
                               __global float* out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    PhaseQuery q;
    q.wi = vxyz(wi);
    q.wo = vxyz(wo[i]);
    out[i] = phase_eval(row, &q);
}
'''
LOCAL = 64


def phase_row(kind: str, **props):
    """The Phase row of Mitsuba's <phase type="kind"> with float properties `props`, made through its plugin."""
    from clrender.scene.registry import instantiate

    return instantiate("phase", kind, {k: ("float", v) for k, v in props.items()}, fmt="mitsuba").pack()


def _launch(ctx, queue, name, n, *args):
    import pyopencl as cl

    k = cl.Kernel(build_program(ctx, SOURCE), name)
    k(queue, (max(MIN_GENERIC_GLOBAL, -(-n // LOCAL) * LOCAL),), (LOCAL,), *args)


def sample_batch(ctx, queue, row, wi, n: int, seed: int = 7):
    """(wo (n, 3), weight (n,), pdf (n,)) of n samples of `row` at wi."""
    import pyopencl as cl

    mf = cl.mem_flags
    d_row = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(np.atleast_1d(row)))
    out, pdf = np.empty((n, 4), np.float32), np.empty(n, np.float32)
    d_out, d_pdf = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes), cl.Buffer(ctx, mf.WRITE_ONLY, pdf.nbytes)
    _launch(ctx, queue, "phase_sample_batch", n, d_row, np.array([*wi, 0], np.float32), np.uint32(n),
            np.uint32(seed), d_out, d_pdf)
    cl.enqueue_copy(queue, out, d_out)
    cl.enqueue_copy(queue, pdf, d_pdf)
    queue.finish()
    return out[:, :3], out[:, 3], pdf


def eval_batch(ctx, queue, row, wi, wo) -> np.ndarray:
    import pyopencl as cl

    mf = cl.mem_flags
    wo4 = np.zeros((len(wo), 4), np.float32)
    wo4[:, :3] = wo
    d_row = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(np.atleast_1d(row)))
    d_wo = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=wo4)
    out = np.empty(len(wo), np.float32)
    d_out = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
    _launch(ctx, queue, "phase_eval_batch", len(wo), d_row, np.array([*wi, 0], np.float32), np.uint32(len(wo)),
            d_wo, d_out)
    cl.enqueue_copy(queue, out, d_out)
    queue.finish()
    return out


def chi2_of(ctx, queue, sample_row, pdf_row, wi, n: int, res: int = 12, peak_width: float = 0.3, n_tests: int = 1,
            alpha: float = 0.01):
    """The chi-square test of n samples of `sample_row` at wi against the density of `pdf_row` (the same row for
    the real test), over a (res cos theta, 2 res phi) grid integrated on a partition refined around the forward
    and backward directions (where hg peaks); and the samples."""
    wo, w, pdf = sample_batch(ctx, queue, sample_row, wi, n)
    wi = np.asarray(wi, np.float64)
    peaks = [(tuple(-wi), peak_width), (tuple(wi), peak_width)]
    dirs, weights, cell = refined_direction_grid(res, 8, peaks, n_fine=400)
    dens = eval_batch(ctx, queue, pdf_row, wi, dirs)
    exp = expected_from_grid(dens, weights, cell, (res, 2 * res), n)
    return chi2_test(bin_directions(wo, res), exp, alpha=alpha, n_tests=n_tests), exp, (wo, w, pdf)
