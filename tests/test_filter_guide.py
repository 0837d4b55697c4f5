"""The guided filter sampling the renderer uses (filter_sample_guided over the CDF + guide table of
clrender/filters/filter.py's with_guide) gives exactly the offsets and weights of the bisection in
filter_sample, which tests/filters/ check statistically."""
import numpy as np
import pyopencl as cl
import pytest

from clrender.device.program import build_program
from clrender.filters.filter import with_guide
from clrender.testing.plugin_checks import filter_camera

# the filters of tests/filters/ whose sampling the bisection's statistical tests check
FILTERS = {"box": ("box", ""), "box_wide": ("box", '<float name="radius" value="1.5"/>'),
           "tent": ("tent", '<float name="radius" value="1.2"/>'), "gaussian": ("gaussian", ""),
           "mitchell": ("mitchell", "")}

SRC = r"""
#include "filter.h"
__kernel void both(__global const Camera* cam, __global const float* cdf, __global const float* table,
                   __global const float2* u, __global float4* out, uint n) {
    uint i = get_global_id(0);
    if (i >= n) return;
    float w0, w1;
    float2 a = filter_sample(cam, cdf, u[i], &w0);
    float2 b = filter_sample_guided(cam, table, u[i], &w1);
    out[2 * i] = (float4)(a.x, a.y, w0, 0.0f);
    out[2 * i + 1] = (float4)(b.x, b.y, w1, 0.0f);
}
"""


def test_guide_table():
    cdf = np.array([0.0, 0.0, 0.1, 0.1, 0.7, 0.7, 1.0, 1.0, 1.0], np.float32)     # empty bins on purpose
    t = with_guide(cdf)
    n = len(cdf) - 1
    assert np.array_equal(t[: n + 1], cdf) and len(t) == 2 * n + 1
    g = t[n + 1:].astype(int)
    for k in range(n):
        u = np.float32(k / n)
        assert cdf[g[k]] <= u and (g[k] == n - 1 or cdf[g[k] + 1] > u)


@pytest.mark.parametrize("name", sorted(FILTERS))
def test_guided_equals_bisection(ctx, queue, name):
    row, cdf = filter_camera(*FILTERS[name]).pack()
    table = with_guide(cdf)
    n = len(cdf) - 1
    rng = np.random.default_rng(3)
    u = rng.integers(0, 1 << 24, (200_000, 2)).astype(np.float32) / np.float32(1 << 24)   # next1d's lattice
    edges = np.concatenate([cdf, np.arange(n) / np.float32(n), np.nextafter(cdf, np.float32(0)),
                            [0.0, 1.0 - 2.0 ** -24]]).astype(np.float32)
    edges = edges[(edges >= 0) & (edges < 1)]
    u = np.concatenate([u, np.stack([edges, edges[::-1]], 1)]).astype(np.float32)
    R = len(u)
    G = -(-R // 64) * 64
    up = np.zeros((G, 2), np.float32)
    up[:R] = u
    mf = cl.mem_flags
    ro = lambda a: cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(a))  # noqa: E731
    out = np.zeros((2 * G, 4), np.float32)
    b_out = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
    k = cl.Kernel(build_program(ctx, SRC), "both")
    k(queue, (G,), (64,), ro(row), ro(cdf), ro(table), ro(up), b_out, np.uint32(R))
    cl.enqueue_copy(queue, out, b_out)
    queue.finish()
    a, b = out[0:2 * R:2], out[1:2 * R:2]
    assert np.array_equal(a, b), f"{(a != b).any(1).sum()} samples differ"
