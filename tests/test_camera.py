"""Camera rays from the kernel against an independent numpy model of Nori's perspective camera
(sample -> camera space through the inverse of Nori's projection matrices, as NORI_FORMAT.md writes them for
each dialect), incl. the mirror convention of each dialect and a degenerate lookat."""
import re

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
    o[i] = vf4(r.o, 0.0f); d[i] = vf4(r.d, 0.0f); clip[i] = (float2)(r.tmin, r.tmax);
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


def test_eth2023_reads_cameras_and_rotations_as_eth():
    """eth2023 is eth but for the analytic sphere's u (tests/shapes/test_sphere.py): the same camera mirror and the
    same unnormalised rotate axes."""
    for inner in ('<rotate axis="0,2,0" angle="90"/>', '<scale value="-1,1,1"/><lookat origin="1,2,3" '
                  'target="0,0.5,-1" up="0,1,0"/>'):
        eth, eth2023 = (camera_from_xml(inner, dialect=d) for d in ("eth", "eth2023"))
        np.testing.assert_array_equal(eth2023.to_world.matrix, eth.to_world.matrix)
        assert eth2023.mirror_x == eth.mirror_x != camera_from_xml(inner).mirror_x


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


FAR = """<scene><integrator type="normals"/><camera type="perspective">
    <integer name="width" value="6"/><integer name="height" value="4"/><float name="fov" value="2"/>{clip}
    <rfilter type="box"/>
    <transform name="toWorld"><lookat origin="0,0,0" target="0,0,-1" up="0,1,0"/></transform></camera>
  <mesh type="sphere"><point name="center" value="0,0,-3e4"/><float name="radius" value="1e4"/></mesh></scene>"""
MITSUBA_FAR = """<scene version="3.0.0"><integrator type="depth"/><sensor type="{kind}">{clip}
    <transform name="to_world"><lookat origin="0,0,0" target="0,0,-1" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="6"/><integer name="height" value="4"/><rfilter type="box"/>
    </film></sensor>
  <shape type="sphere"><point name="center" value="0,0,-3e4"/><float name="radius" value="1e4"/></shape></scene>"""


@pytest.mark.parametrize("value", ["inf", "+inf", "Infinity"])
def test_far_clip_inf_means_no_far_clipping(tmp_path, value):
    """A sphere 2e4 away, beyond the default far clip of 1e4: unseen by default, seen everywhere with farClip (Nori)
    or far_clip (Mitsuba: perspective and orthographic) = inf, at its true depth."""
    import clrender

    for text, clip, check in (
            (FAR.replace("{clip}", "{c}"), '<float name="farClip" value="{v}"/>',
             lambda img: np.abs(img).sum(axis=-1) > 0.5),                  # a normal where the sphere is seen
            (MITSUBA_FAR.replace("{kind}", "perspective").replace("{clip}", "{c}"),
             '<float name="far_clip" value="{v}"/><float name="fov" value="2"/>',
             lambda img: np.abs(img[..., 0] - 2e4) < 2e4 * 1e-3),           # depth: the distance along the ray
            (MITSUBA_FAR.replace("{kind}", "orthographic").replace("{clip}", "{c}"),
             '<float name="far_clip" value="{v}"/>', lambda img: np.abs(img[..., 0] - 2e4) < 2e4 * 1e-3)):
        for given, seen in (("", False), (clip.format(v=value), True)):
            (tmp_path / "far.xml").write_text(text.format(c=given))
            img = clrender.render(clrender.load_scene(tmp_path / "far.xml"), spp=1).image
            assert check(img).all() if seen else not check(img).any(), (given, img[..., 0])


@pytest.mark.parametrize("xml, what", [
    (FAR.format(clip='<float name="farClip" value="-inf"/>'), "number '-inf' in attribute value"),
    (FAR.format(clip='<float name="farClip" value="1e999"/>'), "infinite (or too large"),
    (FAR.format(clip='<float name="fov" value="inf"/>').replace('<float name="fov" value="2"/>', ""),
     "number 'inf' of 'fov' is infinite"),
    (FAR.format(clip="").replace('name="radius" value="1e4"', 'name="radius" value="inf"'),
     "number 'inf' of 'radius' is infinite"),
    (MITSUBA_FAR.format(kind="thinlens", clip='<float name="far_clip" value="inf"/>'
                                              '<float name="aperture_radius" value="0.1"/>'), "needs a focus_distance"),
    (MITSUBA_FAR.format(kind="perspective", clip='<float name="far_clip" value="inf"/>').replace(
        '<integrator type="depth"/>', '<emitter type="constant"><rgb name="radiance" value="inf"/></emitter>'),
     "number 'inf' in attribute value"),
])
def test_inf_elsewhere_is_an_error(tmp_path, xml, what):
    import clrender
    from clrender.errors import SceneError

    (tmp_path / "s.xml").write_text(xml)
    with pytest.raises(SceneError, match=re.escape(what)) as e:
        clrender.load_scene(tmp_path / "s.xml")
    assert str(e.value).startswith(f"{tmp_path / 's.xml'}:"), str(e.value)
