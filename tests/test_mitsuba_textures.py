"""Mitsuba 3 textures where a float parameter reads them (clrender/textures/bitmap.py, checkerboard.py): the float
view (a bitmap's luminance, a checkerboard's other cell) on the host, on the device and against Mitsuba 3.9.1's
eval_1, and blend weights and mask opacities given as floats, bitmaps, colours and rawconstant in a furnace. The
bitmap's own lookups, image formats and errors are tested in tests/textures/test_bitmap.py."""
import numpy as np
import pytest
from PIL import Image

from clrender import plugins  # noqa: F401  (registers the plugins)
from clrender.scene import registry
from clrender.scene.transform import Transform
from clrender.testing.plugin_checks import texture_eval_batch
from textures.image_common import bitmap, mitsuba_lookups, random_png, real_mitsuba


@pytest.fixture(scope="module")
def png(tmp_path_factory):
    return random_png(tmp_path_factory.mktemp("tex"))


# ------------------------------------------------------------------------- a texture where a float parameter takes it
LUM = np.array([0.212671, 0.715160, 0.072169])


def checkerboard(c0, c1, to_uv=None):
    p = {"color0": ("color", c0), "color1": ("color", c1)}
    if to_uv is not None:
        p["to_uv"] = ("transform", to_uv)
    return registry.instantiate("texture", "checkerboard", p, fmt="mitsuba")


def test_float_view_is_mitsubas_float_lookup(png):
    """A roughness, blend weight or opacity texture is read as Mitsuba's eval_1 reads it: a bitmap's luminance
    (not its red channel), and for a checkerboard the channel mean of the *other* cell's colour (Mitsuba 3.9.1's
    float lookup tests the cells the other way round from its colour lookup)."""
    path, img = png
    t = bitmap(path, raw=True, filter_type="nearest")
    v = t.float_view()
    assert v is t.float_view() and v.float_view() is v          # one object, so the table holds it once
    np.testing.assert_allclose(v.image, np.repeat((img / 255.0 @ LUM)[..., None], 3, -1), rtol=1e-6)
    np.testing.assert_allclose(t.image, img / 255.0, atol=1e-7)   # the colour lookup is unchanged
    c = checkerboard([0.9, 0.1, 0.2], [0.05, 0.3, 0.7])
    np.testing.assert_allclose(c.float_view().eval([[0.2, 0.2], [0.7, 0.2]]), [[0.35] * 3, [0.4] * 3])
    np.testing.assert_allclose(c.eval([[0.2, 0.2]]), [[0.9, 0.1, 0.2]])


def test_float_view_on_the_device(ctx, queue, png):
    path, _ = png
    t, c = bitmap(path), checkerboard([0.9, 0.1, 0.2], [0.05, 0.3, 0.7], Transform.scale([3, 2, 1]))
    uv = np.random.default_rng(8).uniform(-1, 2, size=(500, 2))
    views = [t.float_view(), c.float_view()]
    for v, dev in zip(views, texture_eval_batch(ctx, queue, views, uv)):
        np.testing.assert_allclose(dev, v.eval(uv.astype(np.float32)), rtol=1e-5, atol=5e-5)


def test_float_view_matches_mitsuba(tmp_path, png):
    """Against Mitsuba 3's own eval_1 at random uvs (PNG sRGB and raw, EXR, a checkerboard with to_uv)."""
    mi = real_mitsuba("Mitsuba 3 is not installed (pip install mitsuba==3.9.1): it checks the float lookup")
    mi.set_variant("scalar_rgb")
    path, _ = png
    exr = np.random.default_rng(9).uniform(0, 3, size=(4, 6, 3)).astype(np.float32)
    mi.Bitmap(exr).write(str(tmp_path / "t.exr"))
    cases = [(bitmap(path), {"type": "bitmap", "filename": str(path)}),
             (bitmap(path, raw=True), {"type": "bitmap", "filename": str(path), "raw": True}),
             (bitmap(tmp_path / "t.exr"), {"type": "bitmap", "filename": str(tmp_path / "t.exr")}),
             (checkerboard([0.9, 0.1, 0.2], [0.05, 0.3, 0.7], Transform.scale([3, 2, 1])),
              {"type": "checkerboard", "color0": {"type": "rgb", "value": [0.9, 0.1, 0.2]},
               "color1": {"type": "rgb", "value": [0.05, 0.3, 0.7]}, "to_uv": mi.ScalarTransform4f().scale([3, 2, 1])})]
    uv = np.random.default_rng(10).uniform(0.01, 0.99, size=(200, 2))
    for ours, d in cases:
        want = mitsuba_lookups(mi, d, uv, float_lookup=True)
        np.testing.assert_allclose(ours.float_view().eval(uv)[:, 0], want, rtol=2e-5, atol=1e-6, err_msg=d["type"])


FURNACE = """<scene version="3.0.0">
    <sensor type="perspective"><float name="fov" value="30"/>
        <film type="hdrfilm"><integer name="width" value="6"/><integer name="height" value="6"/>
            <rfilter type="box"/></film></sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="10"/><rotate y="1" angle="180"/><translate z="2"/></transform>
        {bsdf}
    </shape>
</scene>"""
BLACK, WHITE = ('<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>',
                '<bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf>')


@pytest.mark.parametrize("bsdf, expect", [
    # blend of black and white under a unit sky: the weight; a mask over black: 1 - opacity
    (f'<bsdf type="blendbsdf">{{tex}}{BLACK}{WHITE}</bsdf>', lambda w: w),
    (f'<bsdf type="mask">{{tex}}{BLACK}</bsdf>', lambda w: 1 - w),
], ids=["blendbsdf weight", "mask opacity"])
@pytest.mark.parametrize("given", ["float", "bitmap", "rgb", "rawconstant"])
def test_float_parameter_in_a_furnace(tmp_path, bsdf, expect, given):
    """A coloured texture (or colour) where a float is read renders as Mitsuba reads it: the bitmap's luminance, the
    colour's channel mean (a red-channel reading gives 0.9 or 0.1 here). The blend's black child reflects nothing,
    but the directions it samples are samples of the mixture (they were once dropped: 0.2 for 0.4)."""
    import clrender
    from clrender.testing.stats import compare_mean_to_value

    rgb = np.array([230, 51, 26], np.uint8)
    name = "weight" if "blend" in bsdf else "opacity"
    if given == "float":
        tex, w = f'<float name="{name}" value="0.4"/>', 0.4
    elif given == "bitmap":
        Image.fromarray(np.tile(rgb, (2, 2, 1))).save(tmp_path / "c.png")
        tex = (f'<texture type="bitmap" name="{name}"><string name="filename" value="c.png"/>'
               f'<boolean name="raw" value="true"/></texture>')
        w = float(rgb / 255.0 @ LUM)
    elif given == "rawconstant":
        tex, w = f'<texture type="rawconstant" name="{name}"><float name="value" value="0.4"/></texture>', 0.4
    else:
        tex = f'<rgb name="{name}" value="{", ".join(str(c / 255) for c in rgb)}"/>'
        w = float((rgb / 255.0).mean())
    (tmp_path / "s.xml").write_text(FURNACE.format(bsdf=bsdf.format(tex=tex)))
    film = clrender.render(clrender.load_scene(tmp_path / "s.xml"), spp=64, seed=2)
    res = compare_mean_to_value(film, expect(w))
    assert res.passed, (res.message, film.image.mean(axis=(0, 1)), expect(w))


def test_blend_of_a_mirror_and_diffuse_in_a_furnace(tmp_path):
    """blendbsdf of a perfect mirror and a diffuse 0.8 at weight 0.5 under a unit sky: exactly 0.5 + 0.5 x 0.8.
    Mitsuba 3.9.1 renders 0.875 here (its blend adds the diffuse child's density to the mirror's discrete
    probability when the mirror is sampled, which darkens the mirror's share; README, known differences)."""
    import clrender
    from clrender.testing.stats import compare_mean_to_value

    bsdf = ('<bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="conductor"/>'
            '<bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf></bsdf>')
    (tmp_path / "s.xml").write_text(FURNACE.format(bsdf=bsdf))
    film = clrender.render(clrender.load_scene(tmp_path / "s.xml"), spp=256, seed=4)
    res = compare_mean_to_value(film, 0.9)
    assert res.passed, (res.message, film.image.mean(axis=(0, 1)))


# ---------------------------------------------------------------------------------------------------- 16-bit PNGs


# ---------------------------------------------------------------------------------------------------- image formats
