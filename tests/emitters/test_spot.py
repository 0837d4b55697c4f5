"""Mitsuba 3's spot light (clrender/emitters/spot.py, kernels/emitters/spot.h) on the device: a delta light, so its
sampling is checked exactly (Mitsuba's falloff, 1 inside the beam and linear in angle to 0 at the cutoff, against
closed-form values; a projected texture as Mitsuba projects it), the texture's nesting error, and a rendered plane
against the closed form. (Set-up: emitter_common.py.)"""
import numpy as np
import pytest

import clrender
from clrender.errors import SceneError
from clrender.scene.transform import Transform

from .emitter_common import device, mitsuba, unit


@pytest.mark.plugin("spot", "sampling")
def test_spot_falloff_closed_form(tmp_path, ctx, queue, kernels):
    pos = np.array([0.5, 3.0, -0.2])
    to_world = Transform.lookat(pos, [0.5, 0.0, -0.2], [0, 0, 1])
    spot = mitsuba("spot", intensity=("color", [2.0, 3.0, 4.0]), cutoff_angle=("float", 30.0),
                   beam_width=("float", 10.0), to_world=("transform", to_world))
    d = device(tmp_path, ctx, queue, kernels, [spot])
    # points at angle theta off the axis (straight down), at distance r from the light
    theta = np.radians([0.0, 5.0, 9.9, 10.1, 15.0, 20.0, 25.0, 29.9, 30.1, 45.0, 90.0, 120.0])
    expect = np.array([1, 1, 1, (30 - 10.1) / 20, 0.75, 0.5, 0.25, 0.1 / 20, 0, 0, 0, 0])
    phi = np.linspace(0, 2 * np.pi, len(theta), endpoint=False)
    leave = np.stack([np.sin(theta) * np.cos(phi), -np.cos(theta), np.sin(theta) * np.sin(phi)], axis=1)
    r = np.linspace(0.5, 4.0, len(theta))
    refs = (pos + leave * r[:, None]).astype(np.float32)
    s = d.sample(0, refs, np.zeros((len(theta), 2), np.float32))
    assert np.all(s["delta"] == 1) and np.all(s["pdf"] == 1)
    np.testing.assert_allclose(s["w"] * r[:, None] ** 2, expect[:, None] * [2.0, 3.0, 4.0], rtol=2e-3, atol=1e-5)
    np.testing.assert_allclose(spot.falloff(leave), expect, atol=1e-9)
    # defaults: cutoff 20, beam 15 (3/4 of the cutoff), intensity 1
    dflt = mitsuba("spot")
    assert (dflt.cutoff, dflt.beam_width) == (20.0, 15.0)
    np.testing.assert_allclose(dflt.falloff(unit([[0, 0, 1], [np.sin(np.radians(17.5)), 0,
                                                              np.cos(np.radians(17.5))]])), [1, 0.5])


SPOT_WITH_TEXTURE = """<scene version="3.0.0">
    <sensor type="perspective"><transform name="to_world"><lookat origin="0, 4, 4" target="0, 0, 0" up="0, 1, 0"/>
        </transform><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film>
    </sensor>
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="4"/></transform>
    </shape>
    <emitter type="spot">
        <rgb name="intensity" value="2, 3, 4"/>
        <float name="cutoff_angle" value="40"/>
        <float name="beam_width" value="25"/>
        <texture type="checkerboard" name="texture">
            <rgb name="color0" value="0.9, 0.5, 0.1"/><rgb name="color1" value="0.1, 0.2, 0.7"/>
            <transform name="to_uv"><scale x="3" y="2"/></transform>
        </texture>
        <transform name="to_world"><lookat origin="0.3, 3, -0.2" target="0.3, 0, -0.2" up="0, 0, 1"/></transform>
    </emitter>
</scene>"""


def test_spot_projects_its_texture_as_mitsuba(tmp_path, ctx, queue, kernels):
    """Mitsuba 3.9.1's spot with a `texture`: the intensity times the texture at direction_to_uv of the local direction
    (0.5 + 0.5 (x, y) / (z tan cutoff)); outside the cone, nothing (and no lookup)."""
    (tmp_path / "spot.xml").write_text(SPOT_WITH_TEXTURE)
    spot = next(e for e in clrender.load_scene(tmp_path / "spot.xml").emitters if type(e).__name__ == "SpotEmitter")
    assert spot.texture is not None
    d = device(tmp_path, ctx, queue, kernels, [spot])
    rng = np.random.default_rng(3)
    theta = np.radians(rng.uniform(0.0, 45.0, 400))
    phi = rng.uniform(0.0, 2 * np.pi, 400)
    leave = np.stack([np.sin(theta) * np.cos(phi), -np.cos(theta), np.sin(theta) * np.sin(phi)], axis=1)
    r = rng.uniform(0.5, 3.0, 400)
    refs = (spot.position + leave * r[:, None]).astype(np.float32)
    s = d.sample(0, refs, np.zeros((400, 2), np.float32))
    expect = spot.falloff(leave)[:, None] * spot.texture.eval(spot.uv(leave)) * [2.0, 3.0, 4.0]
    inside = spot.falloff(leave) > 0
    assert inside.sum() > 200 and (~inside).sum() > 20
    # away from the checker edges (float rounding of uv may pick the other square there)
    st = spot.uv(leave) * [3, 2]
    clear = np.all(np.abs(st * 2 - np.round(st * 2)) > 1e-3, axis=1)
    np.testing.assert_allclose((s["w"] * r[:, None] ** 2)[clear], expect[clear], rtol=2e-3, atol=1e-5)
    # the texture is what varies: both colours show up inside the cone
    assert len(np.unique(np.round(expect[inside & clear, 0], 6))) > 5


def test_spot_texture_must_be_nested_by_its_name(tmp_path):
    (tmp_path / "s.xml").write_text(SPOT_WITH_TEXTURE.replace('name="texture"', 'name="intensity"'))
    with pytest.raises(SceneError, match="takes a texture named 'texture'"):
        clrender.load_scene(tmp_path / "s.xml")


SPOT_OVER_A_PLANE = """<scene version="3.0.0"><integrator type="path"/>
    <sensor type="perspective"><float name="fov" value="0.002"/>
        <transform name="to_world"><lookat origin="3.3, 0.4, 1.5" target="0.8, 0.3, 0" up="0, 0, 1"/></transform>
        <film type="hdrfilm"><integer name="width" value="2"/><integer name="height" value="2"/><rfilter type="box"/>
        </film></sensor>
    <shape type="rectangle"><transform name="to_world"><scale value="10"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>
    <emitter type="spot"><rgb name="intensity" value="5, 4, 3"/><float name="cutoff_angle" value="30"/>
        <float name="beam_width" value="20"/>
        <transform name="to_world"><lookat origin="0, 0, 2" target="0, 0, 0" up="0, 1, 0"/></transform></emitter>
</scene>"""


@pytest.mark.plugin("spot", "render")
def test_spot_over_a_plane(tmp_path):
    """A spot 2 above a diffuse plane lights the point the camera sees, 23 degrees off its axis, in its falloff's
    ramp (between the beam's 20 and the cutoff's 30 degrees): rho / pi x I x falloff x cos / d^2; noiseless. (The
    falloff changes by a tenth per degree there: the camera is narrow enough, 0.002 degrees, that its pixels see the
    same value to 1e-4.)"""
    (tmp_path / "spot.xml").write_text(SPOT_OVER_A_PLANE)
    scene = clrender.load_scene(tmp_path / "spot.xml")
    spot = next(e for e in scene.emitters if type(e).__name__ == "SpotEmitter")
    d = np.array([0.8, 0.3, 0.0]) - [0.0, 0.0, 2.0]
    r = np.linalg.norm(d)
    falloff = spot.falloff(d / r)
    assert 0.3 < falloff < 0.9, falloff
    value = 0.5 / np.pi * np.array([5.0, 4.0, 3.0]) * falloff * (2.0 / r) / r ** 2
    film = clrender.render(scene, spp=16, seed=1)
    np.testing.assert_allclose(film.image, np.broadcast_to(value, film.image.shape), rtol=1e-3)
