"""Mitsuba sensors and films: the field of view conversions against numbers Mitsuba 3.9 gives, crop windows, the
orthographic sensor's rays, and the thin lens (every ray of a film position through one point of the plane in focus; origins uniform on the
aperture disk, by a chi-square test)."""
import numpy as np
import pyopencl as cl
import pytest

from clrender.device.program import build_program
from clrender.scene.registry import create
from clrender.scene.xmlparser import parse_string
from clrender.testing.chi2 import bin_points_2d, chi2_test, integration_points_2d

SRC = r"""
#include "camera.h"
__kernel void lens_rays(__global const Camera* cam, __global const float4* pos_lens, __global float4* o,
                        __global float4* d, uint n) {
    uint i = get_global_id(0);
    if (i >= n) return;
    float4 a = pos_lens[i];
    Ray r = camera_ray_lens(cam, a.x, a.y, (float2)(a.z, a.w));
    o[i] = vf4(r.o, r.tmin); d[i] = vf4(r.d, r.tmax);
}
"""


def sensor(inner: str, film: str = '<integer name="width" value="64"/><integer name="height" value="48"/>',
           kind: str = "perspective"):
    import clrender.plugins  # noqa: F401

    xml = f"""<scene version="3.0.0"><sensor type="{kind}">{inner}<film type="hdrfilm">{film}</film></sensor>
              <shape type="cube"/></scene>"""
    return create(parse_string(xml, "s.xml")).camera


# x_fov of Mitsuba 3.9's perspective sensor (mi.load_dict(...) printed) for these parameters and film sizes
@pytest.mark.parametrize("inner, w, h, x_fov", [
    ("", 768, 576, 38.1848),                                                       # 50 mm on the diagonal
    ('<string name="focal_length" value="35mm"/>', 768, 576, 52.62254),
    ('<float name="fov" value="30"/><string name="fov_axis" value="y"/>', 64, 48, 39.32012),
    ('<float name="fov" value="30"/><string name="fov_axis" value="diagonal"/>', 64, 48, 24.19758),
    ('<float name="fov" value="30"/><string name="fov_axis" value="smaller"/>', 64, 48, 39.32012),
    ('<float name="fov" value="30"/><string name="fov_axis" value="larger"/>', 48, 64, 22.72583),
    ('<float name="fov" value="30"/><string name="fov_axis" value="larger"/>', 64, 48, 30.0),
])
def test_field_of_view_as_mitsuba(inner, w, h, x_fov):
    cam = sensor(inner, f'<integer name="width" value="{w}"/><integer name="height" value="{h}"/>')
    assert cam.fov == pytest.approx(x_fov, abs=2e-4)


def test_sensor_defaults_are_mitsubas():
    cam = sensor("", "")
    assert (cam.width, cam.height, cam.sampler.sample_count) == (768, 576, 4)
    assert (cam.near_clip, cam.far_clip) == (0.01, 1e4)
    assert type(cam.filter).__name__ == "MitsubaGaussianFilter" and cam.filter.radius == 2.0
    assert not cam.film.sample_border


def test_crop_window_is_the_image():
    cam = sensor("", '<integer name="width" value="64"/><integer name="height" value="48"/>'
                     '<integer name="crop_offset_x" value="10"/><integer name="crop_offset_y" value="4"/>'
                     '<integer name="crop_width" value="20"/><integer name="crop_height" value="30"/>')
    row, _ = cam.pack()
    assert (cam.width, cam.height) == (20, 30)
    assert (row["width"][0], row["height"][0], row["film_width"][0], row["film_height"][0]) == (20, 30, 64, 48)
    assert (row["crop_x"][0], row["crop_y"][0], row["clip_window"][0]) == (10, 4, 1)
    assert row["inv_aspect"][0] == pytest.approx(48 / 64)


@pytest.fixture(scope="module")
def lens_program(ctx):
    return cl.Kernel(build_program(ctx, SRC), "lens_rays")


def lens_rays(ctx, queue, program, cam, pos_lens):
    row, _ = cam.pack()
    n = len(pos_lens)
    mf = cl.mem_flags
    b_cam = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=row)
    b_in = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(pos_lens, np.float32))
    o = np.zeros((n, 4), np.float32)
    d = np.zeros((n, 4), np.float32)
    bo, bd = cl.Buffer(ctx, mf.WRITE_ONLY, o.nbytes), cl.Buffer(ctx, mf.WRITE_ONLY, d.nbytes)
    program(queue, (((n + 63) // 64) * 64,), (64,), b_cam, b_in, bo, bd, np.uint32(n))
    cl.enqueue_copy(queue, o, bo)
    cl.enqueue_copy(queue, d, bd)
    queue.finish()
    return o, d


LOOK = '<transform name="to_world"><lookat origin="1, 2, 3" target="0, 0.5, -1" up="0, 1, 0"/></transform>'


def test_thin_lens_rays_meet_in_the_focus_plane(ctx, queue, lens_program):
    cam = sensor('<float name="aperture_radius" value="0.25"/><float name="focus_distance" value="4"/>' + LOOK,
                 kind="thinlens")
    pinhole = sensor(LOOK)
    rng = np.random.default_rng(3)
    n = 4096
    pos = np.column_stack([rng.uniform(0, 64, n), rng.uniform(0, 48, n), rng.random(n), rng.random(n)])
    o, d = lens_rays(ctx, queue, lens_program, cam, pos)
    po, pd = lens_rays(ctx, queue, lens_program, pinhole, pos)
    m = cam.to_world.matrix
    axis = m[:3, 2] / np.linalg.norm(m[:3, 2])
    # where each ray meets the plane at distance 4 along the viewing axis, for the lens and the pinhole
    def hit(o, d):
        t = (4.0 - (o[:, :3] - m[:3, 3]) @ axis) / (d[:, :3] @ axis)
        return o[:, :3] + t[:, None] * d[:, :3]
    assert np.abs(hit(o, d) - hit(po, pd)).max() < 2e-4
    lens_offsets = o[:, :3] - m[:3, 3]
    assert np.abs(lens_offsets @ axis).max() < 1e-5                      # origins on the lens plane
    assert np.linalg.norm(lens_offsets, axis=1).max() <= 0.25 * (1 + 1e-5)
    assert np.linalg.norm(lens_offsets, axis=1).max() > 0.24             # and not all at the centre


@pytest.mark.parametrize("kind", ["perspective", "orthographic"])
def test_focus_distance_is_accepted_where_mitsuba_reads_it(ctx, queue, lens_program, kind):
    """Mitsuba 3.9.1 reads focus_distance in every projective sensor's base class (exporters write it on
    perspective sensors); on a pinhole or orthographic sensor it changes no ray."""
    cam = sensor('<float name="focus_distance" value="3"/>' + LOOK, kind=kind)
    plain = sensor(LOOK, kind=kind)
    rng = np.random.default_rng(5)
    pos = np.column_stack([rng.uniform(0, 64, 256), rng.uniform(0, 48, 256), rng.random(256), rng.random(256)])
    for a, b in zip(lens_rays(ctx, queue, lens_program, cam, pos), lens_rays(ctx, queue, lens_program, plain, pos)):
        assert np.array_equal(a, b)
    from clrender.errors import SceneError

    with pytest.raises(SceneError, match="expects a <float>"):
        sensor('<string name="focus_distance" value="far"/>', kind=kind)


@pytest.mark.parametrize("kind", ["perspective", "thinlens", "orthographic"])
def test_shutter_interval_is_accepted_as_in_mitsuba(kind):
    """Every Mitsuba 3.9.1 sensor takes shutter_open/shutter_close (close not before open); nothing moves here."""
    from clrender.errors import SceneError

    lens = '<float name="aperture_radius" value="0.1"/>' if kind == "thinlens" else ""
    cam = sensor(lens + '<float name="shutter_open" value="0.5"/><float name="shutter_close" value="1.5"/>', kind=kind)
    assert cam.fov == sensor(lens, kind=kind).fov
    with pytest.raises(SceneError, match="shutter_close") as e:
        sensor(lens + '<float name="shutter_open" value="1"/>', kind=kind)
    assert e.value.location.line == 1


def test_orthographic_rays_are_parallel_from_the_scaled_film_plane(ctx, queue, lens_program):
    """Mitsuba's orthographic sensor: image position (x, y) of the full film starts at camera-space
    (1 - 2x, (1 - 2y) h/w, near_clip) (the to_world's scale sets the area) and runs along +z for far - near."""
    xform = ('<transform name="to_world"><scale x="2" y="3"/>'
             '<lookat origin="1, 2, 3" target="0, 0.5, -1" up="0, 1, 0"/></transform>')
    cam = sensor(xform + '<float name="near_clip" value="0.5"/><float name="far_clip" value="20"/>',
                 film='<integer name="width" value="64"/><integer name="height" value="48"/>'
                      '<integer name="crop_offset_x" value="8"/><integer name="crop_width" value="40"/>',
                 kind="orthographic")
    rng = np.random.default_rng(5)
    n = 1000
    pos = np.column_stack([rng.uniform(0, 40, n), rng.uniform(0, 48, n), np.zeros(n), np.zeros(n)])
    o, d = lens_rays(ctx, queue, lens_program, cam, pos)
    m = cam.to_world.matrix
    fx, fy = (pos[:, 0] + 8) / 64, pos[:, 1] / 48
    local = np.column_stack([1 - 2 * fx, (1 - 2 * fy) * 48 / 64, np.full(n, 0.5), np.ones(n)])
    np.testing.assert_allclose(o[:, :3], (local @ m.T)[:, :3], atol=2e-5)
    z = m[:3, 2] / np.linalg.norm(m[:3, 2])
    np.testing.assert_allclose(d[:, :3], np.broadcast_to(z, (n, 3)), atol=1e-6)
    assert np.all(o[:, 3] == 0.0) and np.allclose(d[:, 3], 19.5)


def test_thin_lens_origins_are_uniform_on_the_aperture(ctx, queue, lens_program):
    r = 0.5
    cam = sensor(f'<float name="aperture_radius" value="{r}"/>', kind="thinlens")   # camera = world frame
    n, res = 200_000, 16
    rng = np.random.default_rng(11)
    pos = np.column_stack([np.full(n, 20.0), np.full(n, 30.0), rng.random(n), rng.random(n)])
    o, _ = lens_rays(ctx, queue, lens_program, cam, pos)
    observed = bin_points_2d(o[:, :2], (-r, -r), (r, r), res)
    pts, w, cell = integration_points_2d((-r, -r), (r, r), res)
    inside = (np.hypot(pts[:, 0], pts[:, 1]) <= r).astype(np.float64)
    expected = np.bincount(cell, weights=inside * w / (np.pi * r * r), minlength=res * res) * n
    expected = np.append(expected, 0.0)
    result = chi2_test(observed, expected)
    assert result.passed, result.message


def test_thin_lens_needs_its_aperture():
    from clrender.errors import SceneError

    with pytest.raises(SceneError, match="aperture_radius"):
        sensor("", kind="thinlens")


@pytest.mark.parametrize("xform, ok", [
    ('<scale value="2"/>', False), ('<scale x="1.001"/>', False), ('<scale y="0.999"/>', False),
    ('<matrix value="1 0.01 0 0  0 1 0 0  0 0 1 0  0 0 0 1"/>', False),     # shear
    ('<scale x="1.0001"/>', True), ('<scale x="-1"/>', True), ('<rotate y="1" angle="30"/><translate x="2"/>', True),
])
def test_scaled_sensor_is_refused_as_in_mitsuba(xform, ok):
    """Mitsuba 3.9.1 refuses a sensor to_world whose axes are not orthonormal within 1e-3 (checked with
    mi.load_dict for each of these); clrender rendered such a camera with another field of view."""
    from clrender.errors import SceneError

    inner = f'<transform name="to_world">{xform}</transform>'
    if ok:
        sensor(inner)
    else:
        with pytest.raises(SceneError, match="to_world scales or shears"):
            sensor(inner)


def test_principal_point_offset_is_a_shifted_window(tmp_path):
    """principal_point_offset_x/y (which Blender's Mitsuba exporter writes; once an unknown parameter here) shift
    where the image looks by that fraction of the whole film (not of the crop window): the 16 x 8 window at (2, 1) of
    a 20 x 10 film shifted by (0.25, -0.1) sees what the window at (17, 5) of a 40 x 20 film of twice the
    tan(fov / 2) sees (the convention checked against Mitsuba 3.9.1 renders)."""
    import clrender
    from clrender.testing.stats import compare_films

    def scene(name, sensor, film):
        xml = f"""<scene version="3.0.0">
            <sensor type="perspective">{sensor}
                <transform name="to_world"><lookat origin="0, 1, 4" target="0, 0.3, 0" up="0, 1, 0"/></transform>
                <film type="hdrfilm">{film}<rfilter type="box"/></film></sensor>
            <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
            <shape type="cube"><transform name="to_world"><scale value="0.5"/><rotate y="1" angle="30"/></transform>
                <bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.3, 0.1"/></bsdf></shape>
            <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/>
                <translate y="-0.5"/></transform></shape></scene>"""
        (tmp_path / name).write_text(xml)
        return clrender.load_scene(tmp_path / name)

    fov = 40.0
    wide = np.degrees(2 * np.arctan(2 * np.tan(np.radians(fov / 2))))
    crop = '<integer name="crop_width" value="16"/><integer name="crop_height" value="8"/>'
    small = '<integer name="width" value="20"/><integer name="height" value="10"/>' + crop
    shifted = scene("a.xml", f'<float name="fov" value="{fov}"/><float name="principal_point_offset_x" value="0.25"/>'
                    '<float name="principal_point_offset_y" value="-0.1"/>',
                    small + '<integer name="crop_offset_x" value="2"/><integer name="crop_offset_y" value="1"/>')
    window = scene("b.xml", f'<float name="fov" value="{wide}"/>',
                   '<integer name="width" value="40"/><integer name="height" value="20"/>' + crop +
                   '<integer name="crop_offset_x" value="17"/><integer name="crop_offset_y" value="5"/>')
    plain = scene("c.xml", f'<float name="fov" value="{fov}"/>',
                  small + '<integer name="crop_offset_x" value="2"/><integer name="crop_offset_y" value="1"/>')
    a, b, c = (clrender.render(s, spp=64, seed=k) for k, s in enumerate((shifted, window, plain)))
    assert compare_films(a, b).passed, compare_films(a, b).message
    assert not compare_films(a, c).passed      # the shift is seen


def test_film_takes_mitsubas_output_options():
    """Parameters of Mitsuba 3.9.1's hdrfilm that change only how it writes its file are accepted (banner and
    compensate were once unknown parameters); a pixel format we cannot write is a clear error."""
    from clrender.errors import SceneError

    film = ('<integer name="width" value="8"/><integer name="height" value="6"/><boolean name="banner" value="false"/>'
            '<boolean name="compensate" value="true"/><string name="file_format" value="openexr"/>'
            '<string name="component_format" value="float16"/><string name="pixel_format" value="rgba"/>')
    assert (sensor("", film).width, sensor("", film).height) == (8, 6)
    with pytest.raises(SceneError, match="pixel_format 'xyz' is not supported"):
        sensor("", '<string name="pixel_format" value="xyz"/>')
