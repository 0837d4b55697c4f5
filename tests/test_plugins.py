"""A plugin is its .py, its .h and one registration: test-only plugins (kernels in tests/kernels/) registered
here reach the kernels through the generated dispatch, pack their typed parameter rows, declare the flags the
kernels test, and render the analytic answers; a plugin whose header lacks a declared method fails the build."""
from pathlib import Path

import numpy as np
import pytest

import clrender
from clrender.bsdfs.bsdf import Bsdf
from clrender.device import codegen, dispatch
from clrender.emitters.emitter import Emitter, nonnegative_color
from clrender.errors import DeviceError
from clrender.scene import registry
from clrender.scene.registry import create
from clrender.scene.xmlparser import parse_string

HERE = Path(__file__).resolve().parent
CUBE = HERE / "nori" / "cube_inward.obj"


class Tinted(Bsdf):
    """<bsdf type="tinted"><color name="albedo" value="0.5"/><float name="tint" value="1"/></bsdf>"""
    kernel = str(HERE / "kernels" / "tinted.h")
    PARAMS = [("albedo", "float4"), ("tint", "float")]
    FLAGS = ("DIFFUSE",)

    def __init__(self, props, children, spec):
        self.albedo = nonnegative_color(props, "albedo", np.full(3, 0.5))
        self.tint = props.get_float("tint", 1.0)

    def fill(self, p, row, textures):
        p["albedo"][:3] = self.albedo
        p["tint"] = self.tint
        return False


class Skydome(Emitter):
    """<emitter type="skydome"><color name="radiance" value="1"/></emitter>: the upper (+y) hemisphere glows."""
    kernel = str(HERE / "kernels" / "skydome.h")
    PARAMS = [("radiance", "float4")]
    FLAGS = ("INFINITE",)

    def __init__(self, props, children, spec):
        self.radiance = nonnegative_color(props, "radiance")

    def fill(self, p, row, ctx, shape):
        p["radiance"][:3] = self.radiance


@pytest.fixture
def test_plugins():
    registry.register("bsdf", "tinted")(Tinted)
    registry.register("emitter", "skydome")(Skydome)
    try:
        yield
    finally:
        registry.unregister("bsdf", "tinted")
        registry.unregister("emitter", "skydome")


def scene(xml):
    import clrender.plugins  # noqa: F401

    return create(parse_string(xml, "plugins.xml"))


CAMERA = """<camera type="perspective"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>
    <float name="fov" value="{fov}"/><rfilter type="box"/>
    <transform name="toWorld"><lookat origin="{o}" target="{t}" up="{u}"/></transform></camera>"""


def test_registration_generates_dispatch_rows_and_flags(test_plugins):
    src = codegen.dispatch_source(dispatch.BSDF)
    assert f'#include "{Tinted.kernel}"' in src and "return tinted_sample(b, q, u);" in src
    assert "return skydome_eval(sd, em, q);" in codegen.dispatch_source(dispatch.EMITTER)
    assert "TintedParams tinted;" in codegen.c_header()
    t = Tinted.__new__(Tinted)
    t.albedo, t.tint = np.array([0.2, 0.4, 0.6]), 0.5
    row = t.pack()
    assert row["type"] == dispatch.tag_of(Tinted) and row["flags"] == dispatch.flag_defines()["BSDF_DIFFUSE"]
    np.testing.assert_allclose(row["tinted"]["albedo"][:3], [0.2, 0.4, 0.6])
    assert row["tinted"]["tint"] == 0.5
    # tags follow the prefixes, not the import order: registering shifts the later ones, consistently
    tags = [dispatch.tag_of(c) for c in dispatch.plugins("bsdf")]
    assert tags == list(range(len(tags)))


def test_test_only_bsdf_renders_the_furnace(test_plugins):
    """Closed emitting cube (Le = 1) of albedo 0.4 x tint 1.25 = 0.5: path tracing gives Le / (1 - 0.5) = 2."""
    s = scene(f"""<scene><integrator type="path_mis"/>
        {CAMERA.format(w=8, h=8, fov=60, o="0.1,-0.2,0.3", t="0.3,0.2,-1", u="0,0,1")}
        <mesh type="obj"><string name="filename" value="{CUBE}"/>
            <bsdf type="tinted"><color name="albedo" value="0.4"/><float name="tint" value="1.25"/></bsdf>
            <emitter type="area"><color name="radiance" value="1"/></emitter></mesh></scene>""")
    film = clrender.render(s, spp=256, seed=2)
    mean = film.image.mean()
    se = np.sqrt(film.variance().mean() / film.image[..., 0].size)
    assert abs(mean - 2.0) < 5 * se + 1e-3, (mean, se)


def test_test_only_infinite_emitter_lights_a_sphere(test_plugins):
    """A diffuse sphere (albedo 0.8) under a sky of radiance 1 over the upper hemisphere, seen from straight
    above through a 1° field of view: its top receives E = pi, so L = 0.8 (to 1e-4 for the tiny tilt of the
    normals in view). Escaping rays: 1 looking up, 0 looking down (the infinite-emitter list is used)."""
    sphere = '<mesh type="sphere"><float name="radius" value="1"/><bsdf type="diffuse"><color name="albedo" value="0.8"/></bsdf></mesh>'
    sky = '<emitter type="skydome"><color name="radiance" value="1"/></emitter>'
    top = scene(f"""<scene><integrator type="path_mis"/>{CAMERA.format(w=4, h=4, fov=1, o="0,5,0", t="0,0,0", u="0,0,1")}
        {sphere}{sky}</scene>""")
    film = clrender.render(top, spp=512, seed=1)
    se = np.sqrt(film.variance().mean() / 16)
    assert abs(film.image.mean() - 0.8) < 5 * se + 2e-4, (film.image.mean(), se)
    up = scene(f"""<scene><integrator type="path_mis"/>{CAMERA.format(w=4, h=4, fov=20, o="5,0,0", t="5,1,0", u="0,0,1")}
        {sphere}{sky}</scene>""")
    np.testing.assert_allclose(clrender.render(up, spp=4).image, 1.0, rtol=1e-6)
    down = scene(f"""<scene><integrator type="path_mis"/>{CAMERA.format(w=4, h=4, fov=20, o="5,0,0", t="5,-1,0", u="0,0,1")}
        {sphere}{sky}</scene>""")
    assert np.all(clrender.render(down, spp=4).image == 0)


class Broken(Bsdf):
    kernel = str(HERE / "kernels" / "tinted.h")   # defines tinted_*, not broken_*
    prefix = "broken"
    FLAGS = ("DIFFUSE",)

    def __init__(self, props, children, spec):
        pass


def test_a_declared_method_missing_from_the_header_fails_the_build(ctx):
    from clrender.device.program import build_program

    registry.register("bsdf", "broken")(Broken)
    try:
        with pytest.raises(DeviceError, match="broken_eval"):
            build_program(ctx, '#include "bsdf.h"\n__kernel void k(__global const Bsdf* b, __global float* o) '
                               '{ BsdfQuery q; q.wi = q.wo = v3(0.0f, 0.0f, 1.0f); o[0] = bsdf_pdf(b, &q); }')
    finally:
        registry.unregister("bsdf", "broken")
