"""Mitsuba 3.9's `sunsky` (clrender/emitters/sunsky.py, kernels/emitters/sunsky.h): the sky evaluated on the device
from coefficients the host interpolates in Mitsuba's tables, importance sampled through envmap's functions by a map
of it, and the sun as a `distantdisk` row.

* the sky as the device renders it (and black below the horizon, with no sampling density there), against the
  Hosek-Wilkie formula evaluated here, written afresh from the published model (scalar loops over the tables:
  turbidity and albedo lerps, the quintic Bézier in elevation); the sun's radiance likewise from the irradiance
  table and the CIE matching functions;
* the sun's position from a date: solstice noons, whose elevation is 90° − latitude ± 23.44° by astronomy;
* chi-square of the sky's and the sun's sampling against their pdfs (the machinery of tests/test_emitters.py);
* a render: a diffuse plane under the sun and sky, whose radiance is ρ/π times the irradiance integrated here;
* a twin scene of our own against Mitsuba 3.9.1's render of it (sunsky_twin.xml / .npz, make_sunsky_ref.py);
* an Oclgrind run of a sunsky render (out-of-bounds reads of the sky's coefficient rows);
* refusals: located errors naming the parameter (an old file's unknown one too), and without the `sunsky` extra
  one naming the extra.

The refusals and the missing-extra error run without the tables; the rest needs the `sunsky` extra and is skipped
without it, saying so.
"""
import importlib.metadata
import math
from pathlib import Path

import numpy as np
import pytest

import clrender
from clrender.emitters import sunsky
from clrender.errors import SceneError
from clrender.loader import load_scene
from clrender.pack import pack_scene
from clrender.scene import registry
from clrender.scene.cie_tables import CIE1931_X, CIE1931_Y, CIE1931_Z
from clrender.scene.transform import Transform
from clrender.testing.stats import compare_mean_to_value

from .emitter_common import HEADER, Dev, kernels, run_chi2, tris_obj, quad  # noqa: F401  (kernels: a fixture)

try:
    TABLES = sunsky.tables()
except SceneError:
    TABLES = None
needs_tables = pytest.mark.skipif(TABLES is None, reason="needs the sunsky extra: pip install clrender[sunsky]")

K_CIE = 1.0 / 106.7502593994140625


def make(**props):
    return registry.instantiate("emitter", "sunsky", props, fmt="mitsuba")


def unit(v):
    v = np.asarray(v, np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# ------------------------------------------------------------------------- the model, written here from the paper
def formula_coefficients(turbidity, albedo, elevation):
    """(3 channels) x (9 coefficients A..I) and the 3 mean radiances, by explicit loops."""
    P, R = TABLES["sky_params_rgb"], TABLES["sky_rad_rgb"]
    ti = min(int(turbidity - 1.0), 8)
    tw = turbidity - 1.0 - ti
    x = (2.0 * elevation / math.pi) ** (1.0 / 3.0)
    bern = [math.comb(5, k) * x ** k * (1.0 - x) ** (5 - k) for k in range(6)]
    coefs, mean = np.zeros((3, 9)), np.zeros(3)
    for c in range(3):
        a = albedo[c]
        for k in range(6):
            def at(table, *rest):
                t0 = (1 - a) * table[(ti, 0, k, c) + rest] + a * table[(ti, 1, k, c) + rest]
                t1 = (1 - a) * table[(ti + 1, 0, k, c) + rest] + a * table[(ti + 1, 1, k, c) + rest]
                return (1 - tw) * t0 + tw * t1
            mean[c] += bern[k] * at(R)
            for j in range(9):
                coefs[c, j] += bern[k] * at(P, j)
    return coefs, mean


def formula_sky(coefs, mean, cos_theta, gamma):
    """Hosek & Wilkie 2012, eq. 9 with Mitsuba's arrangement of the nine coefficients, times Mitsuba's CIE
    normalisation; arrays of directions."""
    ct, g = np.asarray(cos_theta)[..., None], np.asarray(gamma)[..., None]
    A, B, C, D, E, F, G, H, I = coefs.T
    chi = (1 + np.cos(g) ** 2) / (1 + I * I - 2 * I * np.cos(g)) ** 1.5
    L = (1 + A * np.exp(B / (ct + 0.01))) * (C + D * np.exp(E * g) + F * np.cos(g) ** 2 + G * chi + H * np.sqrt(ct))
    return L * mean * K_CIE


def formula_sun(turbidity, elevation, half_angle):
    """Uniform solar radiance: the irradiance table at 320..720 nm in 40 nm steps to linear sRGB (CIE 1931
    matching functions, Rec. 709 primaries; the mean over the 11 wavelengths, 320 nm lying outside the CIE
    table), Mitsuba's conversion constant, over the disk's solid angle."""
    irr = TABLES["sun_irradiance"]
    ti = min(int(turbidity - 1.0), 8)
    tw = turbidity - 1.0 - ti
    e = min(max((math.degrees(elevation) - 2.0) / 3.0, 0.0), 29.999)
    ei = min(int(e), 28)
    ew = e - ei
    spec = [(1 - tw) * ((1 - ew) * irr[ti, ei, w] + ew * irr[ti, ei + 1, w])
            + tw * ((1 - ew) * irr[ti + 1, ei, w] + ew * irr[ti + 1, ei + 1, w]) for w in range(11)]
    to_rgb = np.array([[3.240479, -1.537150, -0.498535], [-0.969256, 1.875991, 0.041556],
                       [0.055648, -0.204043, 1.057311]])
    rgb = np.zeros(3)
    for w in range(1, 11):          # 360..720 nm: every 8th entry of the 5 nm table
        i = 8 * (w - 1)
        rgb += to_rgb @ [CIE1931_X[i], CIE1931_Y[i], CIE1931_Z[i]] * spec[w]
    return rgb / 11 * 467.069280386 * K_CIE / (2 * math.pi * (1 - math.cos(half_angle)))


def device(tmp, ctx, queue, kernels, emitter, stem="s"):
    (tmp / "ground.obj").write_text(tris_obj(quad([0, 0, 0], [0, 0, 5], [5, 0, 0])))
    (tmp / f"{stem}.xml").write_text(HEADER + '<mesh type="obj"><string name="filename" value="ground.obj"/>'
                                     '</mesh>\n</scene>\n')
    scene = load_scene(tmp / f"{stem}.xml")
    scene.emitters.append(emitter)
    return Dev(ctx, queue, kernels, pack_scene(scene))


CASES = {  # name: properties, world-from-local rotation
    "direction-t2": (dict(sun_direction=("vector", np.array([0.3, -0.5, 0.6])), turbidity=("float", 2.0),
                          albedo=("color", np.array([0.1, 0.5, 0.9]))), None),
    "default-yup": (dict(to_world=("transform", Transform.rotate([1, 0, 0], -90.0))),
                    np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])),
    "evening-t7": (dict(hour=("float", 18.25), turbidity=("float", 7.5)), None),
}


@needs_tables
@pytest.mark.parametrize("case", list(CASES))
def test_device_sky_and_sun_match_the_formula(tmp_path, ctx, queue, kernels, case):
    props, rot = CASES[case]
    em = make(**props)
    rot = np.eye(3) if rot is None else rot
    np.testing.assert_allclose(em.to_world, rot, atol=1e-6)
    sun = em.sun_local                       # local, z up; checked against dates in the next test
    elevation = math.asin(sun[2])
    assert elevation > 0.05
    coefs, mean = formula_coefficients(em.turbidity, em.albedo, elevation)
    rng = np.random.default_rng(11)
    local = unit(rng.normal(size=(3000, 3)))
    local[:, 2] = np.abs(local[:, 2])
    keep = (local[:, 2] > 0.02) & (local @ sun < math.cos(math.radians(1.0)))   # off the horizon and the sun
    local = local[keep]
    expect = formula_sky(coefs, mean, local[:, 2], np.arccos(np.clip(local @ sun, -1, 1)))
    d = device(tmp_path, ctx, queue, kernels, em)
    got = d.environment((local @ rot.T).astype(np.float32))[:, :3]
    # the model evaluated on the device in single precision
    np.testing.assert_allclose(got, expect, rtol=1e-4, atol=1e-8)
    # at the horizon: the sky just above it, nothing just below it (where the map's last lit row would blend
    # into the black one below), and no sampling density there either
    phi = rng.uniform(0, 2 * math.pi, 200)
    for elev, lit in ((0.05, True), (-0.05, False), (-0.3, False), (-20.0, False)):
        e = math.radians(elev)
        edge = np.stack([np.cos(e) * np.cos(phi), np.cos(e) * np.sin(phi), np.full_like(phi, math.sin(e))], axis=1)
        out = d.environment((edge @ rot.T).astype(np.float32))
        if lit:
            expect = formula_sky(coefs, mean, np.maximum(edge[:, 2], 0), np.arccos(np.clip(edge @ sun, -1, 1)))
            np.testing.assert_allclose(out[:, :3], expect, rtol=1e-4)
            assert np.all(d.pdf_dirs(0, np.zeros(3), (edge @ rot.T).astype(np.float32)) > 0)
        else:
            assert np.all(out[:, :3] == 0), (elev, out[:, :3].max())
            assert np.all(d.pdf_dirs(0, np.zeros(3), (edge @ rot.T).astype(np.float32)) == 0)
    # the sun: its disk adds the uniform solar radiance to the sky there
    centre = d.environment((rot @ sun)[None].astype(np.float32))[0, :3]
    sky_there = formula_sky(coefs, mean, np.array([sun[2]]), np.array([0.0]))[0]
    np.testing.assert_allclose(centre - sky_there, formula_sun(em.turbidity, elevation, em.half_aperture),
                               rtol=1e-4)
    outside = rot @ unit(sun + 1.5 * em.half_aperture * unit(np.cross(sun, [0, 0, 1])))
    assert np.all(d.environment(outside[None].astype(np.float32))[0, :3] < 0.01 * centre)


@needs_tables
@pytest.mark.parametrize("lat, month, expect_x", [(40.0, 6, 1.0), (-33.0, 12, -1.0)])
def test_sun_at_solstice_noon(lat, month, expect_x):
    """At 12:00 UTC on the Greenwich meridian on a solstice the sun culminates at 90° − |lat − δ|, δ = ±23.44°,
    due south north of the tropics (local +x in Mitsuba's frame, whose code puts the sun at azimuth 180° there)
    and due north south of them (−x)."""
    em = make(latitude=("float", lat), longitude=("float", 0.0), timezone=("float", 0.0), year=("integer", 2010),
              month=("integer", month), day=("integer", 21), hour=("float", 12.0))
    decl = 23.44 if month == 6 else -23.44
    assert math.degrees(em.sun_elevation) == pytest.approx(90.0 - abs(lat - decl), abs=0.15)
    assert np.sign(em.sun_local[0]) == expect_x and abs(em.sun_local[1]) < 0.01


# ------------------------------------------------------------------------------------------------- sampling
@needs_tables
@pytest.mark.plugin("sunsky", "sampling")
@pytest.mark.parametrize("part", [0, 1])
def test_chi2_sky_and_sun_sampling(tmp_path, ctx, queue, kernels, part):
    """Row 0 is the sky map, row 1 the sun (given a 60° aperture here so that its cone spans many cells)."""
    em = make(sun_direction=("vector", np.array([0.6, 0.2, 0.35])), turbidity=("float", 4.0),
              sun_aperture=("float", 60.0))
    d = device(tmp_path, ctx, queue, kernels, em)
    assert len(d.b.emitters) == 2
    r = run_chi2(d, part, np.zeros(3), 0, 300_000, 16, seed=300 + part, n_tests=2)
    assert r.passed, r.message
    assert r.dof >= 10, r.dof
    # each sample's weight is eval / pdf, and pdf() agrees with the sample's pdf
    s = d.sample(part, np.zeros(3), np.random.default_rng(7).random((20_000, 2), dtype=np.float32))
    ok = s["pdf"] > 0
    assert ok.mean() > 0.999
    if part == 0:   # the sky's samples never go below the horizon (this wide sun's cone does: see the docstring)
        assert np.all(s["wi"][ok] @ (em.to_world @ [0, 0, 1]) >= -1e-6)
    np.testing.assert_allclose(s["pdf_again"][ok], s["pdf"][ok], rtol=1e-5)
    np.testing.assert_allclose(s["w"][ok] * s["pdf"][ok, None], s["eval"][ok], rtol=2e-4, atol=1e-7)


# -------------------------------------------------------------------------------------------------- render
def plane_scene(tmp, emitter_xml, up="z"):
    """A large diffuse plane (reflectance 0.5) seen from straight above: every pixel sees it, and it sees only
    the sky's upper hemisphere."""
    rot = "" if up == "z" else '<rotate x="1" angle="-90"/>'
    cam = "0, 0, 1" if up == "z" else "0, 1, 0"
    look_up = "0, 1, 0" if up == "z" else "0, 0, -1"
    xml = f"""<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="perspective"><float name="fov" value="10"/>
        <transform name="to_world"><lookat origin="{cam}" target="0, 0, 0" up="{look_up}"/></transform>
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
        <film type="hdrfilm"><integer name="width" value="12"/><integer name="height" value="12"/>
            <rfilter type="box"/></film></sensor>
    <shape type="rectangle"><transform name="to_world"><scale value="1000"/>{rot}</transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
    {emitter_xml}
</scene>"""
    (tmp / "plane.xml").write_text(xml)
    return tmp / "plane.xml"


@needs_tables
@pytest.mark.parametrize("up, emitter_xml", [
    ("z", '<emitter type="sunsky"><vector name="sun_direction" x="-0.4" y="0.3" z="0.5"/>'
          '<float name="turbidity" value="2.5"/></emitter>'),
    ("y", '<emitter type="sunsky"><float name="hour" value="10"/><float name="turbidity" value="6"/>'
          '<rgb name="albedo" value="0.2, 0.4, 0.6"/><transform name="to_world"><rotate x="1" angle="-90"/>'
          '</transform></emitter>'),
])
@pytest.mark.plugin("sunsky", "render")
def test_plane_under_sun_and_sky(tmp_path, up, emitter_xml):
    scene = load_scene(plane_scene(tmp_path, emitter_xml, up))
    em = scene.emitters[0]
    sun = em.sun_local
    elevation = math.asin(sun[2])
    coefs, mean = formula_coefficients(em.turbidity, em.albedo, elevation)
    # the sky's irradiance of a horizontal plane by the midpoint rule (0.1° x 0.2°), then the sun's: its disk of
    # uniform radiance L and half-angle a delivers L π sin²a cos θ_sun (the disk lies wholly above the horizon)
    th = (np.arange(900) + 0.5) * (math.pi / 2) / 900
    ph = (np.arange(1800) + 0.5) * 2 * math.pi / 1800
    T, Ph = np.meshgrid(th, ph, indexing="ij")
    dirs = np.stack([np.sin(T) * np.cos(Ph), np.sin(T) * np.sin(Ph), np.cos(T)], axis=-1)
    sky = formula_sky(coefs, mean, np.cos(T), np.arccos(np.clip(dirs @ sun, -1, 1)))
    dw = (math.pi / 2 / 900) * (2 * math.pi / 1800) * np.sin(T) * np.cos(T)
    e_sky = (sky * dw[..., None]).sum(axis=(0, 1))
    a = em.half_aperture
    e_sun = formula_sun(em.turbidity, elevation, a) * math.pi * math.sin(a) ** 2 * sun[2]
    expect = 0.5 / math.pi * (e_sky + e_sun)
    film = clrender.render(scene, spp=64, seed=5)
    r = compare_mean_to_value(film, expect, 0.01)
    assert r.passed, (r.message, film.image.reshape(-1, 3).mean(0), expect)


@needs_tables
def test_twin_matches_mitsuba():
    """sunsky_twin.xml (a floor, two spheres, the bare horizon in view), read unchanged by Mitsuba 3.9.1, which
    rendered sunsky_twin.npz (make_sunsky_ref.py: 16 seeds x 256 spp): pixel by pixel and in the image mean,
    as tests/test_mitsuba_twins.py compares its twins."""
    from clrender.testing.stats import compare_image_means, compare_to_reference

    here = Path(__file__).resolve().parent
    with np.load(here / "sunsky_twin.npz") as z:
        mean, stderr, ref_spp = z["mean"], z["stderr"], int(z["spp"])
    scene = load_scene(here / "sunsky_twin.xml")
    film = clrender.render(scene, seed=7)
    result = compare_to_reference(film, mean, stderr, ref_samples=ref_spp, rfilter=scene.camera.filter)
    means = f"means: clrender {film.image.mean(axis=(0, 1)).round(4)}, Mitsuba {mean.mean(axis=(0, 1)).round(4)}"
    assert result.passed, f"{result.message}; {means}"
    overall = compare_image_means(film, mean, stderr, ref_spp, rfilter=scene.camera.filter)
    assert overall.passed, f"{overall.message}; {means}"


# ---------------------------------------------------------------------------------------------------- errors
ONE = '<scene version="3.0.0"><emitter type="sunsky">{}</emitter></scene>'


def load_error(tmp_path, body):
    (tmp_path / "e.xml").write_text(ONE.format(body))
    with pytest.raises(SceneError) as e:
        load_scene(tmp_path / "e.xml")
    return e.value


@pytest.mark.parametrize("body, name, line_of", [   # checked before the tables are read: runs without the extra
    ('<float name="turbidity" value="11"/>', "turbidity", "turbidity"),
    ('<rgb name="albedo" value="0.2, 1.5, 0.2"/>', "albedo", "albedo"),
    ('<float name="sun_scale" value="-1"/>', "sun_scale", "sun_scale"),
    ('<float name="sun_aperture" value="0"/>', "sun_aperture", "sun_aperture"),
    ('<boolean name="complex_sun" value="true"/>', "complex_sun", "complex_sun"),
    ('<vector name="sun_direction" x="0" y="0" z="1"/><float name="hour" value="9"/>', "sun_direction", "hour"),
    ('<transform name="to_world"><scale value="2"/></transform>', "rotation", "to_world"),
])
def test_refusals_are_located(tmp_path, body, name, line_of):
    err = load_error(tmp_path, body)
    assert name in err.message
    assert err.location is not None and err.location.line >= 1 and str(err.location).startswith(str(tmp_path))


def test_the_sky_row_is_laid_out_as_an_envmap_row():
    """kernels/emitters/sunsky.h hands its row to envmap.h's functions, which read the union's envmap member."""
    from clrender.device import layout
    from clrender.emitters.envmap import EnvMap

    row = layout.zeros("Emitter")[0]
    assert sunsky.Sunsky.PARAMS == EnvMap.PARAMS
    assert row["sunsky"].dtype == row["envmap"].dtype
    assert row.dtype.fields["sunsky"][1] == row.dtype.fields["envmap"][1]     # both at the union's start


@needs_tables
def test_old_files_and_unknown_parameters(tmp_path):
    """A Mitsuba 0.6 file's camelCase names are upgraded as Mitsuba 3.9.1 upgrades them (sunDirection, skyScale);
    a parameter Mitsuba 3's sunsky does not have (0.6's sunRadiusScale) is an error naming the ones it has."""
    old = ('<scene version="0.6.0"><emitter type="sunsky"><vector name="sunDirection" x="0" y="0.6" z="0.8"/>'
           '<float name="skyScale" value="2"/>{}</emitter></scene>')
    (tmp_path / "old.xml").write_text(old.format(""))
    # the sunsky loads, both names used (else: "not used"); then the scene stops for its missing sensor
    with pytest.raises(SceneError, match="no sensor"):
        load_scene(tmp_path / "old.xml")
    (tmp_path / "old.xml").write_text(old.format('<float name="sunRadiusScale" value="2"/>'))
    with pytest.raises(SceneError, match=r"sun_radius_scale.*it takes .*sun_direction") as e:
        load_scene(tmp_path / "old.xml")
    assert "hour" in e.value.message and e.value.location.line == 1


def test_without_the_extra_the_error_names_it(tmp_path, monkeypatch, capsys):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(sunsky.importlib.metadata, "distribution", missing)
    err = load_error(tmp_path, "")
    assert 'pip install "clrender[sunsky]"' in err.message and err.location is not None
    from clrender.cli import main

    xml = plane_scene(tmp_path, '<emitter type="sunsky"/>')
    assert main(["render", str(xml), "-o", str(tmp_path / "x.exr"), "-q"]) == 2
    out = capsys.readouterr().err
    assert "clrender[sunsky]" in out and "plane.xml:" in out and "Traceback" not in out


@needs_tables
def test_clean_under_oclgrind(tmp_path):
    """The sky row's coefficient reads after its map's texels, and the rest of a sunsky render, under Oclgrind's
    out-of-bounds and data-race checks (tests/test_oclgrind.py's harness)."""
    from test_oclgrind import _run_under_oclgrind, needs_oclgrind

    if needs_oclgrind.args[0]:
        pytest.skip(needs_oclgrind.kwargs["reason"])
    xml = plane_scene(tmp_path, '<emitter type="sunsky"><float name="hour" value="17"/></emitter>'
                      '<shape type="sphere"><point name="center" value="0, 0, 0.2"/><float name="radius" '
                      'value="0.1"/></shape>')
    proc, report = _run_under_oclgrind(tmp_path, [str(xml), ""])
    assert proc.returncode == 0, proc.stderr
    assert "rendered 2" in proc.stdout
    assert report == "", report[:4000]
