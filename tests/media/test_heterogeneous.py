"""The heterogeneous medium (Mitsuba 3's): reading it with its volumes and Mitsuba's defaults and conventions,
packing its rows, the located refusals; delta tracking and ratio tracking in the kernel against a density ramp's
analytic transmittance (chi-square of the real-collision distances, t-test of the transmittance estimates); and
renders: a constant grid equals the homogeneous medium, a furnace stays at the emission, a ramp's transmittance
seen by camera paths (delta tracking) and by shadow rays (ratio tracking)."""
import numpy as np
import pytest

from clrender import plugins  # noqa: F401
from clrender.errors import SceneError
from clrender.testing.stats import compare_films, compare_mean_to_value, compare_to_value
from clrender.volumes.gridvolume import write_vol

from .media_common import (HEAD, INTERIOR, box, box_to_world, grid_xml, heterogeneous_xml, integrator, medium_xml,
                           ortho_sensor, persp_sensor, ramp, ramp_optical_depth, render_xml)
from .test_homogeneous import err, load, pack_media


def test_defaults_are_mitsubas():
    """sigma_t 1 and albedo 0.75, each a constvolume with the identity to_world, so that (as in Mitsuba 3.9.1) the
    medium's extinction fills only the unit cube; scale 1; majorant scale times the largest sigma_t."""
    s = load('<shape type="sphere"><medium type="heterogeneous" name="interior"/></shape>')
    m = s.shapes[0].interior
    assert m.sigma_t.max_value() == 1 and m.albedo.max_value() == 0.75 and m.scale == 1 and m.majorant == 1
    assert m.sample_emitters and m.spectral and type(m.phase).__name__ == "Isotropic"
    lo, hi = m.sigma_t.bbox()
    np.testing.assert_array_equal(lo, 0) and np.testing.assert_array_equal(hi, 1)


def test_rows_volumes_and_grid_data(tmp_path):
    """A volume is packed once however many media read it (a ref under a name is a medium of its own, reading the
    same grid; each medium's <rgb> albedo is a constvolume of its own); the majorant is scale times the grid's largest value
    over every channel; the grid's voxels land in grid_data; use_grid_bbox maps the file's box onto the cube."""
    grid = np.arange(2 * 3 * 4 * 3, dtype=np.float32).reshape(2, 3, 4, 3) / 100
    write_vol(tmp_path / "g.vol", grid, bbox=(-1, -2, -3, 1, 2, 3))
    from clrender.pack import PackContext, _pack_media
    from clrender.device import layout
    vol = grid_xml("sigma_t", tmp_path / "g.vol", extra='<boolean name="use_grid_bbox" value="true"/>')
    s = load(f'<medium type="heterogeneous" id="smoke">{vol}<rgb name="albedo" value="0.5, 0.6, 0.7"/>'
             '<float name="scale" value="4"/></medium>'
             '<shape type="sphere"><ref id="smoke" name="interior"/></shape>'
             '<shape type="sphere"><ref id="smoke" name="exterior"/></shape>')
    rows = layout.zeros("Shape", len(s.shapes))
    ctx = PackContext()
    _pack_media(s, ctx, rows)
    media = ctx.array("media")[:ctx.size("media")]
    vols = ctx.array("volumes")[:ctx.size("volumes")]
    data = ctx.array("grid_data")[:ctx.size("grid_data")]
    p = media[0]["heterogeneous"]
    assert p["majorant"] == pytest.approx(4 * grid.max()) and p["scale"] == 4
    assert len(media) == 2 and len(vols) == 3 and len(data) == grid.size
    assert media[1]["heterogeneous"]["sigma_t"] == p["sigma_t"] != p["albedo"] != media[1]["heterogeneous"]["albedo"]
    g = vols[p["sigma_t"]]
    np.testing.assert_array_equal(data[g["gridvolume"]["offset"]:][:grid.size], grid.ravel())
    assert tuple(g["gridvolume"]["res"]) == (4, 3, 2, 3)
    np.testing.assert_allclose(g["bbox_min"][:3], (-1, -2, -3)) and np.testing.assert_allclose(g["bbox_max"][:3],
                                                                                                 (1, 2, 3))
    np.testing.assert_allclose(vols[p["albedo"]]["constvolume"]["value"][:3], (0.5, 0.6, 0.7), rtol=1e-6)
    # max_value stands for the grid's largest value (Mitsuba's fixed max): the majorant follows it
    fixed = grid_xml("sigma_t", tmp_path / "g.vol", extra='<float name="max_value" value="3"/>')
    m = load('<shape type="sphere"><medium type="heterogeneous" name="interior"><float name="scale" value="2"/>'
             f'{fixed}</medium></shape>').shapes[0].interior
    assert m.majorant == 6


def test_refusals_are_located(tmp_path):
    write_vol(tmp_path / "neg.vol", np.full((2, 2, 2), -1.0))
    write_vol(tmp_path / "two.vol", np.full((2, 2, 2), 2.0))
    med = '<shape type="sphere"><medium type="heterogeneous" name="interior">\n{}</medium></shape>'
    err(med.format('<volume type="constvolume" name="density"/>'), 2, 'name="sigma_t"', "'density'")
    err(med.format(grid_xml("sigma_t", tmp_path / "neg.vol")), 2, "sigma_t must be non-negative")
    err(med.format(grid_xml("albedo", tmp_path / "two.vol")), 2, "albedo must lie in [0, 1]")
    err(med.format(grid_xml("sigma_t", tmp_path / "missing.vol")), 2, "missing.vol", "not found")
    err(med.format(grid_xml("sigma_t", tmp_path / "two.vol", filter_type="cubic")), 2, "filter_type", "trilinear")
    err(med.format(grid_xml("sigma_t", tmp_path / "two.vol", wrap="border")), 2, "wrap_mode", "repeat")
    err(med.format('<volume type="constvolume" name="sigma_t"/><float name="sigma_t" value="1"/>'), 2, "twice")
    err(med.format('<float name="scale" value="-1"/>'), 2, "scale must be non-negative")
    err('<shape type="sphere">\n<volume type="constvolume" name="sigma_t"/></shape>', 2, "cannot be nested",
        "heterogeneous")


def test_a_volume_referenced_by_id_fills_the_named_parameter(tmp_path):
    s = load('<volume type="constvolume" id="v"><float name="value" value="0.3"/></volume>'
             '<shape type="sphere"><medium type="heterogeneous" name="interior"><ref id="v" name="albedo"/>'
             '<ref id="v" name="sigma_t"/></medium></shape>')
    m = s.shapes[0].interior
    assert m.albedo.max_value() == m.sigma_t.max_value() == pytest.approx(0.3) and m.majorant == pytest.approx(0.3)


# ------------------------------------------------------------------------------------------------ tracking
RAMP_HEIGHT = 2.0


def ramp_scene(tmp_path, scale: float = 1.0):
    """A scene whose one medium is the ramp grid (tests/media/media_common.py ramp) in the box [-1, 1]^2 x [-1, 1]
    (its density grows with z); the slab shape around it is wider, so the box bounds the extinction."""
    import clrender

    write_vol(tmp_path / "ramp.vol", ramp())
    med = heterogeneous_xml(grid_xml("sigma_t", tmp_path / "ramp.vol", box_to_world((1, 1, 1))),
                            '<float name="albedo" value="0"/>', scale=scale, mid="m")
    xml = (f'{HEAD}{integrator("volpath")}{med}{ortho_sensor((0, 0, 5), (0, 0, -10), 0.5, 4, 4)}'
           f'{box((3, 3, 2), inner=INTERIOR.format("m"))}</scene>')
    (tmp_path / "ramp.xml").write_text(xml)
    return clrender.load_scene(tmp_path / "ramp.xml")


# rays through the ramp: origin, direction, t1; the first starts at the box's bottom face, the second below the
# box (the clip to the box), the third obliquely from inside
RAYS = [((0.2, -0.3, -1.0), (0, 0, 1), RAMP_HEIGHT), ((0.0, 0.0, -2.5), (0, 0, 1), 5.0),
        ((0.1, 0.0, -0.5), (0.6, 0.0, 0.8), 1.5)]


def ray_optical_depth(o, d, t):
    """The ramp's optical depth (per channel) from o to o + t d: its density depends on z alone, so it is the
    z-integral over |d_z|."""
    z0 = np.clip(o[2] + 1.0, 0.0, RAMP_HEIGHT)
    z1 = np.clip(o[2] + np.asarray(t, np.float64) * d[2] + 1.0, 0.0, RAMP_HEIGHT)
    g = ramp()
    return (ramp_optical_depth(g, RAMP_HEIGHT, z1) - ramp_optical_depth(g, RAMP_HEIGHT, z0)) / abs(d[2])


def test_ramp_optical_depth_is_the_grids_integral():
    """The analytic optical depth agrees with a fine quadrature of the host's trilinear lookup (GridVolume.eval,
    the kernel's twin): what the kernel tests below hold the kernel to is the grid's."""
    from clrender.volumes.gridvolume import GridVolume
    vol = GridVolume.__new__(GridVolume)
    vol.data, vol.channels, vol.filter, vol.wrap = ramp(), 3, 0, 2
    vol.to_world = np.diag([2.0, 2.0, 2.0, 1.0])
    vol.to_world[:3, 3] = -1
    z = np.linspace(-1, 1, 200001)
    dens = vol.eval(np.stack([np.zeros_like(z), np.zeros_like(z), z], -1))
    quad = ((dens[1:] + dens[:-1]) / 2 * np.diff(z)[:, None]).sum(axis=0)
    np.testing.assert_allclose(quad, ramp_optical_depth(ramp(), RAMP_HEIGHT, [RAMP_HEIGHT])[0], rtol=1e-6)


@pytest.mark.plugin("heterogeneous", "sampling")
@pytest.mark.parametrize("ray", range(len(RAYS)))
def test_ratio_tracking_is_the_analytic_transmittance(ctx, queue, tmp_path, ray):
    """Ratio tracking's estimates (per channel) average to exp(-optical depth): a t-test on each channel."""
    from scipy import stats
    from clrender.testing.chi2 import sidak
    from clrender.testing.media import medium_track_batch

    o, d, t1 = RAYS[ray]
    d = np.asarray(d, np.float64) / np.linalg.norm(d)
    est = medium_track_batch(ctx, queue, ramp_scene(tmp_path), o, d, t1, 1 << 17, "ratio", seed=11 + ray)
    expected = np.exp(-ray_optical_depth(o, d, [t1])[0])
    assert np.all(est >= 0) and np.all(est <= 1)
    t = (est.mean(axis=0) - expected) / (est.std(axis=0, ddof=1) / np.sqrt(len(est)))
    p = 2 * stats.t.sf(np.abs(t), len(est) - 1)
    assert p.min() > sidak(0.01, 3), f"mean {est.mean(axis=0)}, expected {expected}, t {t}"


@pytest.mark.plugin("heterogeneous", "sampling")
@pytest.mark.parametrize("ray,channel", [(0, 0), (1, 1), (2, 2)])
def test_delta_tracking_collisions_follow_their_density(ctx, queue, tmp_path, ray, channel):
    """Delta tracking's first real collision for one channel has the density sigma(t) exp(-tau(t)) along the ray
    and misses it with probability exp(-tau(t1)): chi-square over 24 distance bins and the miss."""
    from clrender.testing.chi2 import chi2_test
    from clrender.testing.media import medium_track_batch

    o, d, t1 = RAYS[ray]
    d = np.asarray(d, np.float64) / np.linalg.norm(d)
    n = 1 << 17
    t = medium_track_batch(ctx, queue, ramp_scene(tmp_path), o, d, t1, n, "delta", channel, seed=5 + ray)
    assert np.all((t > 0) & (t < t1) | np.isinf(t))
    edges = np.linspace(0, t1, 25)
    cdf = 1 - np.exp(-ray_optical_depth(o, d, edges)[:, channel])
    expected = np.append(np.diff(cdf), 1 - cdf[-1]) * n
    observed = np.append(np.histogram(t[np.isfinite(t)], edges)[0], np.isinf(t).sum())
    r = chi2_test(observed, expected, n_tests=3)
    assert r.passed, r.message


# ------------------------------------------------------------------------------------------------ renders
SIGMA = (0.5, 1.0, 2.0)


def lit_box(medium: str, spp: int = 256, size: int = 12) -> str:
    """A null-bounded box holding `medium` (id "m") on a diffuse floor under a rectangular light, seen from the
    front (volpath)."""
    return (f'{HEAD}{integrator("volpath", 12)}{medium}{persp_sensor((0.4, 1.0, 3.5), (0, 0.6, 0), 40, size, spp)}'
            f'<shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/>'
            f'</transform><bsdf type="diffuse"><rgb name="reflectance" value="0.6"/></bsdf></shape>'
            f'<shape type="rectangle"><transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/>'
            f'<translate y="2.2"/></transform><emitter type="area"><rgb name="radiance" value="10"/></emitter>'
            f'</shape>{box((0.6, 0.5, 0.5), centre=(0, 0.6, 0), inner=INTERIOR.format("m"))}</scene>')


@pytest.mark.plugin("heterogeneous", "render")
@pytest.mark.parametrize("albedo,phase", [((0.9, 0.7, 0.5), '<phase type="hg"><float name="g" value="0.5"/></phase>'),
                                          ((0.3, 0.3, 0.3), '<phase type="isotropic"/>')])
def test_a_constant_grid_renders_as_the_homogeneous_medium(tmp_path, albedo, phase):
    """The same box of medium, homogeneous (closed-form flights) and heterogeneous with a constant 3-channel grid
    (delta and ratio tracking against a majorant twice the largest extinction: null collisions in every channel):
    equal per pixel (z-test of two independent renders)."""
    grid = np.broadcast_to(np.asarray(SIGMA, np.float32) / 2, (2, 2, 2, 3))
    write_vol(tmp_path / "c.vol", grid)
    # a voxel of twice the value the box never reaches (outside the box, nearest lookups) doubles the majorant
    spiked = np.array(grid)
    spiked[1, 1, 1] = 2 * np.max(SIGMA) / 2
    write_vol(tmp_path / "s.vol", spiked)
    rgb = ", ".join(str(a) for a in albedo)
    hom = render_xml(tmp_path, lit_box(medium_xml(SIGMA, albedo, phase, mid="m")), seed=1, name="hom.xml")
    big = box_to_world((1.2, 1.0, 1.0), centre=(0.6, 1.1, 0.5))   # the box fills voxel (0, 0, 0)
    het = heterogeneous_xml(grid_xml("sigma_t", tmp_path / "s.vol", big, filter_type="nearest"),
                            f'<volume type="constvolume" name="albedo"><rgb name="value" value="{rgb}"/></volume>',
                            scale=2.0, phase=phase, mid="m")
    film = render_xml(tmp_path, lit_box(het), seed=2, name="het.xml")
    r = compare_films(film, hom)
    assert r.passed, f"{r.message}; means {film.image.mean(axis=(0, 1))} vs {hom.image.mean(axis=(0, 1))}"


@pytest.mark.plugin("heterogeneous", "render")
def test_furnace_radiance_is_the_emission(tmp_path):
    """A smoke-like colour grid (albedo 1) in a constant environment of radiance 1 behind a null boundary: every
    path ends in the environment, so every pixel is 1 (per-pixel z-test), however the density varies."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "mitsuba"))
    from make_volumes import smoke

    s = smoke((8, 10, 6))
    write_vol(tmp_path / "s.vol", np.stack([s, 0.5 * s, 0.25 + s], axis=-1))
    med = heterogeneous_xml(grid_xml("sigma_t", tmp_path / "s.vol", box_to_world((1, 1, 1))),
                            '<float name="albedo" value="1"/>', scale=6.0,
                            phase='<phase type="hg"><float name="g" value="0.6"/></phase>', mid="fog")
    xml = (f'{HEAD}{integrator("volpath")}{med}{persp_sensor((0, 0, 4), (0, 0, 0), 30, 8, 256)}'
           f'{box((1, 1, 1), inner=INTERIOR.format("fog"))}'
           f'<emitter type="constant"><rgb name="radiance" value="1"/></emitter></scene>')
    film = render_xml(tmp_path, xml)
    r = compare_to_value(film, 1.0)
    assert r.passed, f"{r.message}; image mean {film.image.mean(axis=(0, 1))}"


RADIANCE = np.array([2.0, 1.0, 0.5])


def ramp_slab(tmp_path) -> str:
    """The absorbing ramp (albedo 0) filling a null slab |z| <= 1, 40 wide: its medium and its shape."""
    write_vol(tmp_path / "ramp.vol", ramp())
    med = heterogeneous_xml(grid_xml("sigma_t", tmp_path / "ramp.vol", box_to_world((20, 20, 1))),
                            '<float name="albedo" value="0"/>', mid="slab")
    return med + box((20, 20, 1), inner=INTERIOR.format("slab"))


def check_every_pixel(film, expected) -> None:
    """Every pixel (per-pixel z-test) and the image mean (which a bias of a few percent cannot hide in) are the
    expected value."""
    for r in (compare_to_value(film, expected), compare_mean_to_value(film, expected)):
        assert r.passed, f"{r.message}; image mean {film.image.mean(axis=(0, 1))}, expected {expected}"


@pytest.mark.plugin("gridvolume", "render")
@pytest.mark.parametrize("kind", ["volpath", "volpathmis"])
def test_camera_rays_through_a_ramp_see_its_transmittance(tmp_path, kind):
    """An orthographic camera looks down through an absorbing ramp (albedo 0) at an emitter: every pixel is
    L exp(-optical depth) (delta tracking in the integrator, spectral MIS; per-pixel z-test)."""
    xml = (f'{HEAD}{integrator(kind)}{ramp_slab(tmp_path)}{ortho_sensor((0, 0, 5), (0, 0, -10), 0.5, 8, 1024)}'
           f'<shape type="rectangle"><transform name="to_world"><scale value="30"/><translate z="-3"/></transform>'
           f'<emitter type="area"><rgb name="radiance" value="2, 1, 0.5"/></emitter></shape></scene>')
    film = render_xml(tmp_path, xml)
    expected = RADIANCE * np.exp(-ramp_optical_depth(ramp(), RAMP_HEIGHT, [RAMP_HEIGHT])[0])
    check_every_pixel(film, expected)


@pytest.mark.plugin("gridvolume", "render")
def test_shadow_rays_through_a_ramp_see_its_transmittance(tmp_path):
    """A diffuse floor under an absorbing ramp, lit straight down by a directional light through it and seen from
    below the ramp (max_depth 2: direct light only): every pixel is rho / pi E exp(-optical depth), the
    transmittance of the shadow rays (ratio tracking in the integrator; per-pixel z-test)."""
    xml = (f'{HEAD}{integrator("volpath", 2)}{ramp_slab(tmp_path)}'
           f'{ortho_sensor((0, 0, -1.2), (0, 0, -10), 0.5, 8, 256)}'
           f'<shape type="rectangle"><transform name="to_world"><scale value="30"/><translate z="-1.5"/>'
           f'</transform><bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>'
           f'<emitter type="directional"><vector name="direction" value="0, 0, -1"/>'
           f'<rgb name="irradiance" value="2, 1, 0.5"/></emitter></scene>')
    film = render_xml(tmp_path, xml)
    expected = 0.5 / np.pi * RADIANCE * np.exp(-ramp_optical_depth(ramp(), RAMP_HEIGHT, [RAMP_HEIGHT])[0])
    check_every_pixel(film, expected)


def test_a_grid_a_little_outside_its_range_is_clamped(tmp_path, caplog):
    """Interpolation ringing (lajolla's coloured smoke: down to -0.004 of a 1.6 peak) is clamped with a warning,
    as Mitsuba renders such grids unchecked; further out stays refused (test_refusals_are_located)."""
    d = np.full((2, 2, 2), 1.6)
    d[0, 0, 0] = -0.004
    write_vol(tmp_path / "ring.vol", d)
    a = np.full((2, 2, 2), 0.5)
    a[1, 1, 1] = 1.004
    write_vol(tmp_path / "alb.vol", a)
    with caplog.at_level("WARNING", logger="clrender"):
        m = load('<shape type="sphere"><medium type="heterogeneous" name="interior">'
                 f'{grid_xml("sigma_t", tmp_path / "ring.vol")}{grid_xml("albedo", tmp_path / "alb.vol")}'
                 '</medium></shape>').shapes[0].interior
    assert m.sigma_t.min_value() == 0 and m.albedo.max_value() == 1
    assert "ring.vol" in caplog.text and "alb.vol" in caplog.text and "clamped" in caplog.text


@pytest.mark.plugin("homogeneous", "render")
def test_a_homogeneous_medium_with_an_albedo_grid(tmp_path):
    """Mitsuba's homogeneous medium may take its albedo from a volume (its docs' textured subsurface scene): with a
    colour grid of albedos (nearest lookups, varying across the box) it renders as the heterogeneous medium of the
    same constant extinction and the same albedo grid (closed-form flights against delta tracking: per-pixel z-test
    of two independent renders), and a constvolume albedo gives the very image of the plain colour. The albedo is
    looked up at the scattering point (at the ray's origin instead, the z-test fails)."""
    import re

    write_vol(tmp_path / "alb.vol", np.random.default_rng(3).uniform(0.1, 0.95, (3, 4, 5, 3)))
    write_vol(tmp_path / "c.vol", np.broadcast_to(np.asarray(SIGMA, np.float32), (2, 2, 2, 3)))
    albedo = grid_xml("albedo", tmp_path / "alb.vol", box_to_world((0.6, 0.5, 0.5), centre=(0, 0.6, 0)),
                      filter_type="nearest")
    plain = medium_xml(SIGMA, (0.4, 0.6, 0.8), mid="m")
    hom = re.sub(r'<rgb name="albedo" value="[^"]*"/>', albedo, plain)
    big = box_to_world((1.2, 1.0, 1.0), centre=(0.6, 1.1, 0.5))
    het = heterogeneous_xml(grid_xml("sigma_t", tmp_path / "c.vol", big, filter_type="nearest"), albedo, mid="m")
    a = render_xml(tmp_path, lit_box(hom), seed=1, name="hom.xml")
    b = render_xml(tmp_path, lit_box(het), seed=2, name="het.xml")
    r = compare_films(a, b)
    assert r.passed, f"{r.message}; means {a.image.mean(axis=(0, 1))} vs {b.image.mean(axis=(0, 1))}"
    const = re.sub(r'<rgb name="albedo" value="[^"]*"/>',
                   '<volume type="constvolume" name="albedo"><rgb name="value" value="0.4, 0.6, 0.8"/></volume>', plain)
    same = [render_xml(tmp_path, lit_box(m, spp=16), seed=3, name=f"c{i}.xml") for i, m in enumerate((plain, const))]
    assert np.array_equal(same[0].image, same[1].image)
