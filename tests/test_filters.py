"""Reconstruction filters: the kernel's offset sampling matches its own tabulated pdf (chi-square), and the
weighted samples reproduce the filter itself (so an image converges to integral f L / integral f)."""
import numpy as np
import pyopencl as cl
import pytest
from scipy import stats
from scipy.integrate import trapezoid

from clrender.device.program import build_program
from clrender.scene.registry import create
from clrender.scene.xmlparser import parse_string
from clrender.testing.chi2 import chi2_test

SRC = r"""
#include "rng.h"
#include "filter.h"
__kernel void offsets(__global const Camera* cam, __global const float* cdf, __global float4* out, uint n, uint seed) {
    uint i = get_global_id(0);
    if (i >= n) return;
    Sampler s;
    sampler_init(&s, seed, i, 0u);
    float w;
    float2 off = filter_sample(cam, cdf, next2d(&s), &w);
    out[i] = (float4)(off.x, off.y, w, 0.0f);
}
"""
FILTERS = {
    "box": "",
    "box_wide": '<float name="radius" value="1.5"/>',
    "tent": '<float name="radius" value="1.2"/>',
    "gaussian": "",
    "mitchell": "",
}
N = 400_000


def make_camera(name):
    import clrender.plugins  # noqa: F401

    ftype = name.split("_")[0]
    xml = (f'<scene><integrator type="normals"/><camera type="perspective"><integer name="width" value="8"/>'
           f'<integer name="height" value="8"/><rfilter type="{ftype}">{FILTERS[name]}</rfilter></camera></scene>')
    return create(parse_string(xml, "f.xml")).camera


@pytest.fixture(scope="module")
def kernel(ctx):
    return cl.Kernel(build_program(ctx, SRC), "offsets")


def run(ctx, queue, kernel, cam, n=N, seed=7):
    row, table = cam.pack()
    mf = cl.mem_flags
    b_cam = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=row)
    b_cdf = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=table)
    out = np.zeros((n, 4), np.float32)
    b_out = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
    kernel(queue, (((n + 63) // 64) * 64,), (64,), b_cam, b_cdf, b_out, np.uint32(n), np.uint32(seed))
    cl.enqueue_copy(queue, out, b_out)
    queue.finish()
    return out, table


def cell_masses(table, radius, edges):
    """Probability of each [edges[k], edges[k+1]) under the piecewise-constant table pdf."""
    cdf = table.astype(np.float64)
    xs = np.linspace(-radius, radius, len(cdf))
    return np.diff(np.interp(edges, xs, cdf))


@pytest.mark.parametrize("name", list(FILTERS))
def test_offsets_follow_their_pdf(ctx, queue, kernel, name):
    cam = make_camera(name)
    out, table = run(ctx, queue, kernel, cam)
    r = cam.filter.radius
    assert np.all(np.abs(out[:, :2]) <= r + 1e-6)
    edges = np.linspace(-r, r, 21)
    obs, _, _ = np.histogram2d(out[:, 0], out[:, 1], bins=[edges, edges])
    m = cell_masses(table, r, edges)
    res = chi2_test(obs, np.outer(m, m) * len(out), alpha=0.01, n_tests=len(FILTERS))
    assert res.passed, res.message


@pytest.mark.parametrize("name", list(FILTERS))
def test_weighted_samples_reproduce_the_filter(ctx, queue, kernel, name):
    """E[w 1{x in cell}] / E[w] must equal integral_cell f / integral f (separable, so per axis)."""
    cam = make_camera(name)
    out, _ = run(ctx, queue, kernel, cam, seed=11)
    f = cam.filter
    r = f.radius
    edges = np.linspace(-r, r, 9)
    x = np.linspace(-r, r, 200001)
    fx = f.eval(x)
    total = trapezoid(fx, x)
    w = out[:, 2].astype(np.float64)
    wy = w  # integrate y out: E[w 1{x in cell}] / E[w]
    zs = []
    for a, b in zip(edges[:-1], edges[1:]):
        sel = (out[:, 0] >= a) & (out[:, 0] < b)
        expect = trapezoid(np.where((x >= a) & (x <= b), fx, 0), x) / total
        v = wy * sel
        ratio = v.sum() / w.sum()
        # delta-method standard error of a ratio of means
        se = np.sqrt(np.var(v - ratio * w) / len(w)) / w.mean()
        zs.append((ratio - expect) / max(se, 1e-12))
    p = 2 * stats.norm.sf(np.max(np.abs(zs)))
    assert p > 1 - (1 - 0.01) ** (1 / (len(FILTERS) * len(zs))), (name, np.round(zs, 2))


def test_a_wrong_table_is_rejected(ctx, queue, kernel):
    """The chi-square above can fail: score gaussian offsets against a box filter's table."""
    cam = make_camera("gaussian")
    out, _ = run(ctx, queue, kernel, cam)
    r = cam.filter.radius
    edges = np.linspace(-r, r, 21)
    obs, _, _ = np.histogram2d(out[:, 0], out[:, 1], bins=[edges, edges])
    m = np.full(20, 1 / 20)
    assert not chi2_test(obs, np.outer(m, m) * len(out)).passed
