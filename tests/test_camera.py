"""Camera rays from the kernel against an independent numpy model of Nori's perspective camera
(sample -> camera space through the inverse of Nori's projection matrices, as NORI_FORMAT.md writes them for
each dialect), incl. the mirror convention of each dialect and a degenerate lookat."""
import numpy as np
import pyopencl as cl
import pytest

from clrender.device.program import build_program
from clrender.scene.xmlparser import parse_string
from clrender.scene.registry import create
from nori_camera import nori_reference

SRC = r"""
#include "camera.h"
__kernel void rays(__global const Camera* cam, __global const float2* pos, __global float4* o,
                   __global float4* d, __global float2* clip, uint n) {
    uint i = get_global_id(0);
    if (i >= n) return;
    Ray r = camera_ray(cam, pos[i].x, pos[i].y);
    o[i] = (float4)(r.o, 0.0f); d[i] = (float4)(r.d, 0.0f); clip[i] = (float2)(r.tmin, r.tmax);
}
"""


def camera_from_xml(inner, width=64, height=48, fov=50.0, dialect="upstream"):
    xml = f"""<scene><integrator type="normals"/><camera type="perspective">
        <integer name="width" value="{width}"/><integer name="height" value="{height}"/>
        <float name="fov" value="{fov}"/><float name="nearClip" value="0.5"/><float name="farClip" value="100"/>
        <transform name="toWorld">{inner}</transform></camera></scene>"""
    import clrender.plugins  # noqa: F401

    return create(parse_string(xml, "cam.xml", nori_dialect=dialect)).camera


@pytest.fixture(scope="module")
def program(ctx):
    return cl.Kernel(build_program(ctx, SRC), "rays")


def kernel_rays(ctx, queue, program, cam, pos):
    row, _ = cam.pack()
    n = len(pos)
    mf = cl.mem_flags
    b_cam = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=row)
    b_pos = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=pos)
    o = np.zeros((n, 4), np.float32)
    d = np.zeros((n, 4), np.float32)
    clip = np.zeros((n, 2), np.float32)
    bo, bd, bc = (cl.Buffer(ctx, mf.WRITE_ONLY, a.nbytes) for a in (o, d, clip))
    program(queue, (((n + 63) // 64) * 64,), (64,), b_cam, b_pos, bo, bd, bc, np.uint32(n))
    for a, b in ((o, bo), (d, bd), (clip, bc)):
        cl.enqueue_copy(queue, a, b)
    queue.finish()
    return o, d, clip


@pytest.mark.parametrize("dialect", ["upstream", "eth"])
@pytest.mark.parametrize("inner", [
    "",
    '<lookat origin="1,2,3" target="0,0.5,-1" up="0,1,0"/>',
    '<scale value="-1,1,1"/><lookat origin="0,1,6.8" target="0,1,0" up="0,1,0"/>',
    '<rotate axis="1,1,0" angle="30"/><translate value="0.5,-2,1"/>',
    '<scale value="2,2,2"/><lookat origin="1,2,3" target="0,0.5,-1" up="0,1,0"/>',
])
def test_camera_rays_match_nori(ctx, queue, program, inner, dialect):
    cam = camera_from_xml(inner, dialect=dialect)
    rng = np.random.default_rng(1)
    pos = np.r_[rng.uniform(0, [64, 48], size=(500, 2)), [[0, 0], [64, 48], [32, 24], [0, 48]]].astype(np.float32)
    o, d, clip = kernel_rays(ctx, queue, program, cam, pos)
    ro, rd, rmin, rmax = nori_reference(64, 48, 50.0, 0.5, 100.0, cam.to_world.matrix, pos.astype(np.float64),
                                        dialect)
    np.testing.assert_allclose(o[:, :3], ro, atol=1e-5)
    np.testing.assert_allclose(d[:, :3], rd, atol=2e-6)
    np.testing.assert_allclose(clip[:, 0], rmin, rtol=1e-5)
    np.testing.assert_allclose(clip[:, 1], rmax, rtol=1e-5)


@pytest.mark.parametrize("dialect,right_is", [("upstream", -1.0), ("eth", 1.0)])
def test_mirror_convention(dialect, right_is):
    """Identity camera: upstream shows camera +x on the image's left, eth on the right; the top is +y."""
    _, d, _, _ = nori_reference(64, 48, 50.0, 0.5, 100.0, np.eye(4), np.array([[60.0, 4.0]]), dialect)
    assert np.sign(d[0, 0]) == right_is and d[0, 1] > 0


@pytest.mark.parametrize("dialect,inner", [
    ("upstream", '<lookat origin="0,0,5" target="0,0,0" up="0,1,0"/>'),
    ("eth", '<scale value="-1,1,1"/><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/>'),
])
def test_each_dialect_idiom_is_unmirrored(ctx, queue, program, dialect, inner):
    """A camera at +z looking at the origin with +y up sees world +x on the image's right when the scene is
    written in its dialect's idiom (plain lookat upstream; scale -1,1,1 before lookat in the ETH forks)."""
    cam = camera_from_xml(inner, dialect=dialect)
    _, d, _ = kernel_rays(ctx, queue, program, cam, np.array([[60.0, 24.0], [4.0, 24.0]], np.float32))
    assert d[0, 0] > 0 > d[1, 0]


def test_rotate_axis_normalisation_differs_by_dialect():
    import clrender.plugins  # noqa: F401

    inner = '<rotate axis="0,2,0" angle="90"/>'
    up = camera_from_xml(inner, dialect="upstream").to_world.matrix[:3, :3]
    eth = camera_from_xml(inner, dialect="eth").to_world.matrix[:3, :3]
    np.testing.assert_allclose(up, [[0, 0, 1], [0, 1, 0], [-1, 0, 0]], atol=1e-12)
    # Eigen's AngleAxis with k = (0,2,0), 90°: c·I + s·[k]x + (1-c)·k·kᵀ
    np.testing.assert_allclose(eth, [[0, 0, 2], [0, 4, 0], [-2, 0, 0]], atol=1e-12)


def test_lookat_with_up_parallel_to_view_is_accepted_with_a_warning(ctx, queue, program, caplog):
    """Nori leaves left = newUp = 0 (Eigen normalises a zero vector to zero): every ray leaves along dir."""
    import logging

    with caplog.at_level(logging.WARNING, logger="clrender"):
        cam = camera_from_xml('<lookat origin="1,2,3" target="1,7,3" up="0,1,0"/>')
    assert any("parallel" in r.getMessage() and "cam.xml:" in r.getMessage() for r in caplog.records)
    pos = np.array([[0, 0], [63.9, 47.9], [10, 30]], np.float32)
    o, d, clip = kernel_rays(ctx, queue, program, cam, pos)
    np.testing.assert_allclose(d[:, :3], np.tile([0, 1, 0], (3, 1)), atol=1e-6)
    np.testing.assert_allclose(o[:, :3], np.tile([1, 2, 3], (3, 1)), atol=1e-6)
    np.testing.assert_allclose(clip[:, 0], 0.5, rtol=1e-5)  # the near plane stays at its distance


def test_unknown_dialect_is_an_error():
    from clrender.errors import ClrenderError

    with pytest.raises(ClrenderError, match="unknown Nori dialect"):
        camera_from_xml("", dialect="mitsuba")
