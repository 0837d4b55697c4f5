"""Mitsuba 3 emitters (clrender/emitters: point, spot, directional, constant, envmap registered for Mitsuba files),
on the device through the kernels of tests/emitters/emitter_common.py.

* directional and point: the irradiance / intensity as Mitsuba names them, the delta lights' errors and defaults;
* selection in proportion to power, and a textured area light.
(spot's and envmap's own tests: tests/emitters/test_spot.py, test_envmap.py.)
"""
import numpy as np
import pytest

import clrender
from clrender.errors import SceneError
from clrender.loader import load_scene
from clrender.device.layout import NONE
from clrender.pack import pack_scene, selection_cdf
from clrender.scene import registry
from clrender.scene.transform import Transform
from clrender.testing.stats import compare_films
from scipy import stats

from emitters.emitter_common import Dev, device, mitsuba, quad, sky_image, tris_obj, unit, write_exr
from emitters.emitter_common import envmaps, kernels  # noqa: F401  (fixtures)


# ------------------------------------------------------------------------------------------------ delta lights
def test_directional_irradiance_and_point_intensity(tmp_path, ctx, queue, kernels):
    rot = Transform.rotate([1, 0, 0], 90.0)     # local +z -> world -y: light travelling straight down
    lights = [mitsuba("directional", irradiance=("color", [1.0, 2.0, 3.0]), direction=("vector", [0.3, -1.0, 0.2])),
              mitsuba("directional", irradiance=("color", 5.0), to_world=("transform", rot)),
              mitsuba("point", intensity=("color", [3.0, 2.0, 1.0]), position=("point", [0.2, 2.0, 0.1])),
              mitsuba("point", to_world=("transform", Transform.translate([1.0, 1.5, -0.5])))]
    d = device(tmp_path, ctx, queue, kernels, lights)
    refs = np.array([[0.5, 0.0, 0.5], [1.0, 0.3, 2.0], [3.0, 0.1, 1.0]], np.float32)
    u = np.zeros((3, 2), np.float32)
    s = d.sample(0, refs, u)
    np.testing.assert_allclose(s["w"], np.broadcast_to([1, 2, 3], (3, 3)), rtol=1e-6)
    np.testing.assert_allclose(s["wi"], np.broadcast_to(-unit([0.3, -1.0, 0.2]), (3, 3)), atol=1e-6)
    s = d.sample(1, refs, u)
    np.testing.assert_allclose(s["w"], 5.0, rtol=1e-6)
    np.testing.assert_allclose(s["wi"], np.broadcast_to([0, 1, 0], (3, 3)), atol=1e-6)
    for e, pos, intensity in ((2, [0.2, 2.0, 0.1], [3, 2, 1]), (3, [1.0, 1.5, -0.5], [1, 1, 1])):
        s = d.sample(e, refs, u)
        r2 = ((refs - np.array(pos)) ** 2).sum(axis=1)
        np.testing.assert_allclose(s["w"] * r2[:, None], np.broadcast_to(intensity, (3, 3)), rtol=1e-4)


def test_delta_light_errors():
    with pytest.raises(SceneError, match="beam_width"):
        mitsuba("spot", cutoff_angle=("float", 10.0), beam_width=("float", 20.0))
    with pytest.raises(SceneError, match="either direction or to_world"):
        mitsuba("directional", direction=("vector", [0, 0, 1]), to_world=("transform", Transform()))
    with pytest.raises(SceneError, match="non-zero"):
        mitsuba("directional", direction=("vector", [0, 0, 0]))


def test_emitter_defaults_are_mitsubas(tmp_path):
    """Every Mitsuba emitter defaults its strength to 1 (mi.load_dict of each prints UniformSpectrum 1): an area
    light written without a radiance (once an error here) is seen as exactly 1."""
    xml = ('<scene version="3.0.0"><sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" '
           'target="0, 0, 0" up="0, 1, 0"/></transform><film type="hdrfilm"><integer name="width" value="4"/>'
           '<integer name="height" value="4"/><rfilter type="box"/></film></sensor>'
           '<shape type="sphere"><float name="radius" value="3"/><emitter type="area"/></shape></scene>')
    (tmp_path / "s.xml").write_text(xml)
    scene = clrender.load_scene(tmp_path / "s.xml")
    film = clrender.render(scene, spp=4, seed=1)
    np.testing.assert_allclose(film.image, 1.0, rtol=1e-6)
    for kind, field in (("point", "power"), ("spot", "intensity"), ("directional", "irradiance"),
                        ("constant", "radiance")):
        value = getattr(mitsuba(kind), field)
        np.testing.assert_allclose(value, 4 * np.pi if kind == "point" else 1.0, err_msg=kind)


# ------------------------------------------------------------------------------- selection in proportion to power
def test_power_selection_chi2_and_pdfs(tmp_path, ctx, queue, kernels, envmaps):
    env, _ = envmaps
    lights = [mitsuba("point", intensity=("color", 100.0), position=("point", [0.5, 2.0, 0.5])),
              mitsuba("spot", intensity=("color", [500.0, 900.0, 200.0]), to_world=("transform", Transform.lookat(
                  [1, 3, 1], [1, 0, 1], [0, 0, 1]))),
              mitsuba("directional", irradiance=("color", 3.0), direction=("vector", [0, -1, 0.2])),
              mitsuba("constant", radiance=("color", 0.2)),
              env]
    d = device(tmp_path, ctx, queue, kernels, lights, selection="power")
    radius = float(d.b.info["bounds_center"][0][3])
    prob = np.diff(np.concatenate([[0.0], selection_cdf([em.selection_power(radius, 0.0) for em in lights])]))
    assert prob.min() > 0.01 and prob.max() < 0.9 and np.ptp(prob) > 0.1      # far from uniform
    n = 200_000
    rng = np.random.default_rng(21)
    refs = np.concatenate([rng.uniform(0.2, 4.8, (n, 1)), np.full((n, 1), 0.01), rng.uniform(0.2, 4.8, (n, 1))], 1)
    s = d.sample(NONE, refs.astype(np.float32), rng.random((n, 3), dtype=np.float32))
    counts = np.bincount(s["emitter"], minlength=len(lights))
    res = stats.chisquare(counts, prob * n)
    assert res.pvalue > 1e-3, (counts, prob * n)
    em = s["emitter"]
    delta = np.isin(em, [0, 1, 2])
    # the pdfs carry the same selection probability: sampling, pdf(), and the environment's sum
    np.testing.assert_allclose(s["pdf"][delta], prob[em[delta]], rtol=1e-5)
    smooth = ~delta & (s["pdf"] > 0)
    np.testing.assert_allclose(s["pdf"][smooth], s["pdf_one"][smooth] * prob[em[smooth]], rtol=2e-4)
    np.testing.assert_allclose(s["pdf_again"][smooth], s["pdf"][smooth], rtol=2e-4)
    np.testing.assert_allclose(s["w"][smooth], s["eval"][smooth] / s["pdf"][smooth, None], rtol=2e-4, atol=1e-6)
    dirs = unit(rng.normal(size=(2000, 3))).astype(np.float32)
    envs = d.environment(dirs)
    one = Dev(d.ctx, d.queue, d.k, d.b)    # the same scene, each infinite light's own pdf
    pdf_c = 1 / (4 * np.pi)
    pdf_env = one.pdf_dirs(4, np.zeros(3), dirs)
    np.testing.assert_allclose(envs[:, 3], prob[3] * pdf_c + prob[4] * pdf_env, rtol=2e-4)
    # uniform selection stays what it was
    u = device(tmp_path, ctx, queue, kernels, lights, stem="u")
    su = u.sample(NONE, refs[:1000].astype(np.float32), rng.random((1000, 3), dtype=np.float32))
    dl = np.isin(su["emitter"], [0, 1, 2])
    np.testing.assert_allclose(su["pdf"][dl], 1 / len(lights))


def test_power_selection_keeps_mis_unbiased(tmp_path):
    """path_mis with a dim large ceiling light, an environment and a very bright small light that faces away
    (most of the power, none of the image): choosing lights by power must give the image of the uniform choice.
    The MIS weights of BSDF samples must use the same selection probabilities as light sampling (with 1/N there,
    the ceiling light's BSDF-sampled share is off by ~30 % here)."""
    write_exr(tmp_path / "sky.exr", sky_image())
    (tmp_path / "small.obj").write_text(tris_obj(quad([2.0, 3.0, 2.0], [0, 0, 0.1], [0.1, 0, 0])))   # faces up, above the ceiling
    (tmp_path / "big.obj").write_text(tris_obj(quad([-2, 2.5, -2], [4, 0, 0], [0, 0, 4])))            # faces down
    (tmp_path / "ground.obj").write_text(tris_obj(quad([-3, 0, -3], [0, 0, 6], [6, 0, 0])))
    xml = ('<scene><integrator type="path_mis"/><camera type="perspective"><float name="fov" value="60"/>'
           '<transform name="toWorld"><lookat origin="0, 2, 1.5" target="0, 0, 0" up="0, 1, 0"/></transform>'
           '<integer name="width" value="10"/><integer name="height" value="8"/></camera>'
           '<mesh type="obj"><string name="filename" value="ground.obj"/><bsdf type="diffuse"/></mesh>'
           '<mesh type="sphere"><point name="center" value="0, 0.5, 0"/><float name="radius" value="0.5"/></mesh>'
           '<mesh type="obj"><string name="filename" value="small.obj"/>'
           '<emitter type="area"><color name="radiance" value="30000"/></emitter></mesh>'
           '<mesh type="obj"><string name="filename" value="big.obj"/>'
           '<emitter type="area"><color name="radiance" value="1"/></emitter></mesh></scene>')
    (tmp_path / "s.xml").write_text(xml)
    films = []
    for sel, seed in (("uniform", 1), ("power", 2)):
        scene = clrender.load_scene(tmp_path / "s.xml")
        scene.emitters.append(mitsuba("envmap", filename=("string", str(tmp_path / "sky.exr")), scale=("float", 0.02)))
        scene.emitter_selection = sel
        films.append(clrender.render(scene, spp=256, seed=seed))
    res = compare_films(*films, alpha=0.01)
    assert res.passed, res.message
    assert films[0].image.mean() > 0.05


def test_cli_power_selection_is_for_mitsuba_scenes(tmp_path, capsys):
    from clrender.cli import main

    (tmp_path / "n.xml").write_text('<scene><integrator type="normals"/><camera type="perspective"><integer '
                                    'name="width" value="4"/><integer name="height" value="4"/></camera></scene>')
    assert main(["render", str(tmp_path / "n.xml"), "--emitter-selection", "power", "-q"]) == 2
    assert "is for Mitsuba scenes" in capsys.readouterr().err


# ---------------------------------------------------------------------------------------- textured area light
LIGHT_OBJ = ("v -1 1 -1\nv 1 1 -1\nv 1 1 1\nv -1 1 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
             "f 1/1 2/2 3/3 4/4\n")   # faces down; uv = ((x + 1) / 2, (z + 1) / 2)


def textured_light_scene(tmp, integrator, to_uv=Transform.scale([2, 2, 1])):
    (tmp / "light.obj").write_text(LIGHT_OBJ)
    (tmp / "ground.obj").write_text(tris_obj(quad([0, 0, 0], [0, 0, 3], [3, 0, 0])))
    xml = (f'<scene><integrator type="{integrator}"/><camera type="perspective"><float name="fov" value="70"/>'
           '<transform name="toWorld"><lookat origin="0, 0.8, 2.5" target="0, 0, 0" up="0, 1, 0"/></transform>'
           '<integer name="width" value="8"/><integer name="height" value="6"/></camera>'
           '<mesh type="obj"><string name="filename" value="ground.obj"/><bsdf type="diffuse"/></mesh>'
           '<mesh type="obj"><string name="filename" value="light.obj"/>'
           '<emitter type="area"><color name="radiance" value="1"/></emitter></mesh></scene>')
    (tmp / "s.xml").write_text(xml)
    scene = load_scene(tmp / "s.xml")
    tex = registry.instantiate("texture", "checkerboard", {"color0": ("color", [4.0, 1.0, 0.5]),
                                                          "color1": ("color", [0.2, 0.5, 3.0]),
                                                          "to_uv": ("transform", to_uv)},
                               fmt="mitsuba")
    light = next(sh for sh in scene.shapes if sh.emitter is not None)
    light.emitter.texture = tex      # what a Mitsuba <emitter type="area"> with a nested radiance texture sets
    return scene, tex


def test_textured_area_light_eval_and_samples(tmp_path, ctx, queue, kernels):
    scene, tex = textured_light_scene(tmp_path, "normals")
    d = Dev(ctx, queue, kernels, pack_scene(scene))
    e = int(d.b.shapes[1]["emitter"])
    rng = np.random.default_rng(31)
    # camera-style rays from below hit the light where the texture is known
    targets = np.concatenate([rng.uniform(-0.99, 0.99, (500, 1)), np.full((500, 1), 1.0),
                              rng.uniform(-0.99, 0.99, (500, 1))], 1)
    org = np.array([0.1, 0.3, -0.2])
    out = d.hit_le(org, unit(targets - org).astype(np.float32))
    uv = np.stack([(targets[:, 0] + 1) / 2, (targets[:, 2] + 1) / 2], 1)
    st = 2 * uv
    frac = st - np.floor(st)
    clear = np.all(np.minimum(np.abs(frac - 0.5), np.minimum(frac, 1 - frac)) > 1e-3, axis=1)
    assert np.all(out[:, 3] == 1)
    np.testing.assert_allclose(out[clear, :3], tex.eval(uv[clear]), rtol=1e-6)
    # light samples: the radiance at the sampled point's uv, weight = eval / pdf
    refs = np.concatenate([rng.uniform(-1.5, 1.5, (2000, 1)), np.full((2000, 1), 0.01),
                           rng.uniform(-1.5, 1.5, (2000, 1))], 1).astype(np.float32)
    s = d.sample(e, refs, rng.random((2000, 2), dtype=np.float32))
    puv = np.stack([(s["p"][:, 0] + 1) / 2, (s["p"][:, 2] + 1) / 2], 1)
    frac = 2 * puv - np.floor(2 * puv)
    clear = np.all(np.minimum(np.abs(frac - 0.5), np.minimum(frac, 1 - frac)) > 1e-3, axis=1)
    np.testing.assert_allclose(s["eval"][clear], tex.eval(puv[clear]), rtol=1e-6)
    np.testing.assert_allclose(s["w"] * s["pdf"][:, None], s["eval"], rtol=2e-4, atol=1e-6)
    assert len(np.unique(s["eval"][:, 0])) == 2     # both colours seen


def test_textured_area_light_strategies_agree(tmp_path):
    """Light sampling (uv of the sampled point) and BSDF sampling (uv of the hit) see the same texture: here one
    colour on the half x < 0 of the light, the other on x > 0 (a wrong uv at sampled points moves the boundary)."""
    films = []
    for k, integrator in enumerate(("path_ems", "path_mats")):
        scene, _ = textured_light_scene(tmp_path, integrator, to_uv=Transform.scale([1, 0.5, 1]))
        films.append(clrender.render(scene, spp=512, seed=k + 1))
    res = compare_films(*films, alpha=0.01)
    assert res.passed, res.message


@pytest.mark.slow
@pytest.mark.parametrize("name", ["spot_point", "checkerboard"])
def test_power_selection_twins_match_mitsuba(name):
    """The twin scenes choosing lights in proportion to power converge to Mitsuba's image (which chooses
    uniformly): only the noise may change."""
    from pathlib import Path

    from clrender.testing.stats import compare_to_reference

    here = Path(__file__).resolve().parent / "mitsuba"
    with np.load(here / "refs" / f"{name}.npz") as z:
        mean, stderr, spp = z["mean"], z["stderr"], int(z["spp"])
    scene = clrender.load_scene(here / "scenes" / f"{name}.xml")
    scene.emitter_selection = "power"
    film = clrender.render(scene, seed=11)
    res = compare_to_reference(film, mean, stderr, ref_samples=spp)
    assert res.passed, res.message
