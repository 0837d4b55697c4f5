"""Camera rays from the kernel against an independent numpy model of Nori's perspective camera
(sample -> camera space through the inverse of Nori's projection matrices), incl. the mirror convention."""
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


def camera_from_xml(inner, width=64, height=48, fov=50.0):
    xml = f"""<scene><integrator type="normals"/><camera type="perspective">
        <integer name="width" value="{width}"/><integer name="height" value="{height}"/>
        <float name="fov" value="{fov}"/><float name="nearClip" value="0.5"/><float name="farClip" value="100"/>
        <transform name="toWorld">{inner}</transform></camera></scene>"""
    import clrender.plugins  # noqa: F401

    return create(parse_string(xml, "cam.xml")).camera


@pytest.fixture(scope="module")
def program(ctx):
    return cl.Kernel(build_program(ctx, SRC), "rays")


@pytest.mark.parametrize("inner", [
    "",
    '<lookat origin="1,2,3" target="0,0.5,-1" up="0,1,0"/>',
    '<scale value="-1,1,1"/><lookat origin="0,1,6.8" target="0,1,0" up="0,1,0"/>',
    '<rotate axis="1,1,0" angle="30"/><translate value="0.5,-2,1"/>',
])
def test_camera_rays_match_nori(ctx, queue, program, inner):
    import clrender.plugins  # noqa: F401

    cam = camera_from_xml(inner)
    row, _ = cam.pack()
    rng = np.random.default_rng(1)
    pos = np.r_[rng.uniform(0, [64, 48], size=(500, 2)), [[0, 0], [64, 48], [32, 24], [0, 48]]].astype(np.float32)
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
    ro, rd, rmin, rmax = nori_reference(64, 48, 50.0, 0.5, 100.0, cam.to_world.matrix, pos.astype(np.float64))
    np.testing.assert_allclose(o[:, :3], ro, atol=1e-5)
    np.testing.assert_allclose(d[:, :3], rd, atol=2e-6)
    np.testing.assert_allclose(clip[:, 0], rmin, rtol=1e-5)
    np.testing.assert_allclose(clip[:, 1], rmax, rtol=1e-5)


def test_mirror_convention():
    """Identity camera: the image's right half looks toward camera +x, the top toward +y. With Nori's
    lookat (whose x column is 'left'), scale -1,1,1 is what makes world +x appear on the right."""
    o, d, _, _ = nori_reference(64, 48, 50.0, 0.5, 100.0, np.eye(4), np.array([[60.0, 4.0]]))
    assert d[0, 0] > 0 and d[0, 1] > 0
    import clrender.plugins  # noqa: F401

    cam = camera_from_xml('<scale value="-1,1,1"/><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/>')
    _, d, _, _ = nori_reference(64, 48, 50.0, 0.5, 100.0, cam.to_world.matrix, np.array([[60.0, 24.0]]))
    assert d[0, 0] > 0, "with the Nori mirror idiom, the image's right side must look toward world +x"
