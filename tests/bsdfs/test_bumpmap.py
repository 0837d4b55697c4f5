"""Mitsuba 3's bumpmap (a wrapper that turns the shading frame by a height texture's slope:
clrender/bsdfs/bumpmap.py, kernels/bsdfs/bumpmap.h and perturb.h) on the device: eval and pdf against Mitsuba 3.9.1
itself at fixed surface points, a height without slope is exactly its child, chi-square of the wrapped sampling for a
tilted frame with weight == f cos / pdf, the scene errors, and a rendered plane with a ramp height against its
closed form (shared set-up: perturbed_common.py; the height bitmap's gradient is checked in
tests/textures/test_bitmap.py)."""
import numpy as np
import pytest

from clrender.errors import SceneError
from clrender.testing.plugin_checks import FAMILIES
from clrender.scene.registry import create

from .perturbed_common import DATA, FLAT_CHILDREN, check_tilted_chi2, check_unperturbed_is_the_child, check_values, spec

#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("bumpmap", "blendbsdf", "conductor", "dielectric", "diffuse", "roughconductor", "roughdielectric",
               "roughplastic"), textures=("bitmap",), levels=2)


TILTED = {   # name: (wrapper dict, wi, uv, the normal the wrapper should reflect about, roughly (for the grid))
    "bumpmap-roughplastic": ({"type": "bumpmap", "scale": 0.5,
                              "h": {"type": "bitmap", "filename": "perturbed_height.png", "raw": True},
                              "bsdf": {"type": "roughplastic", "alpha": 0.3, "distribution": "ggx"}},
                             [0.5, 0.3, 0.8], (0.31, 0.58), 0.3),
}


@pytest.mark.plugin("bumpmap", "eval")
@pytest.mark.parametrize("name", sorted(n for n in DATA["cases"] if n.startswith("bumpmap")))
def test_eval_and_pdf_match_mitsuba(ctx, queue, name):
    check_values(ctx, queue, name)


@pytest.mark.parametrize("child", sorted(FLAT_CHILDREN))
def test_an_unperturbed_wrapper_is_its_child(ctx, queue, child, tmp_path):
    check_unperturbed_is_the_child(ctx, queue, child, tmp_path, "bumpmap")


@pytest.mark.plugin("bumpmap", "sampling")
@pytest.mark.parametrize("name", sorted(TILTED))
def test_chi2_sample_vs_pdf_of_a_tilted_frame(ctx, queue, name):
    check_tilted_chi2(ctx, queue, name, *TILTED[name], n_tests=FAMILIES["perturbed-tilted"])


def test_a_height_texture_without_a_gradient_is_a_located_error():
    d = {"type": "bumpmap", "t": {"type": "checkerboard"}, "bsdf": {"type": "diffuse"}}
    with pytest.raises(SceneError, match="eval_1_grad"):
        create(spec(d))


@pytest.mark.parametrize("d, match", [
    ({"type": "bumpmap", "bsdf": {"type": "diffuse"}}, "one nested <texture>"),
    ({"type": "bumpmap", "h": {"type": "bitmap", "filename": "perturbed_height.png"}}, "one nested <bsdf>"),
], ids=["bumpmap-no-texture", "bumpmap-no-bsdf"])
def test_missing_children_are_errors(d, match):
    with pytest.raises(SceneError, match=match):
        create(spec(d))


# ------------------------------------------------------------------------------------------- render
#: A rectangle (Mitsuba's: [-1, 1]^2 in z = 0, uv = (x + 1, y + 1) / 2, dp/du = (2, 0, 0), dp/dv = (0, 2, 0)) whose
#: height is a linear ramp: under a directional light and in a constant environment, seen from above by a camera
#: that sees only the ramp's inside (uv in [0.15, 0.85]: the bilinear slope is constant between the outer texel
#: centres, 1/16 and 15/16), and whose rays meet it from above the tilted normal as well (no flip_invalid_normals).
RAMP_SCENE = """<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective"><float name="fov" value="20"/>
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="{spp}"/></sampler>
        <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="16"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle">
        <bsdf type="bumpmap"><float name="scale" value="{scale}"/>
            <texture type="bitmap" name="height"><string name="filename" value="ramp.png"/>
                <boolean name="raw" value="true"/></texture>
            <bsdf type="diffuse"><rgb name="reflectance" value="{rho}"/></bsdf>
        </bsdf>
    </shape>
    <emitter type="directional"><vector name="direction" value="{direction}"/>
        <rgb name="irradiance" value="{irradiance}"/></emitter>
    <emitter type="constant"><rgb name="radiance" value="{radiance}"/></emitter>
</scene>"""
RAMP = 16 * np.arange(8)[None, :] + 8 * np.arange(8)[:, None]   # 8 x 8 grey, row j at v = (j + 0.5) / 8
SCALE, RHO, IRRADIANCE, RADIANCE = 2.0, np.array([0.3, 0.6, 0.9]), 3.0, 0.2
TO_LIGHT = np.array([-0.75, 0.75 / np.sqrt(3), 0.5])   # 60 degrees from the plane's normal, at azimuth 150 degrees


def tan2(v):
    return np.maximum(0.0, 1.0 - v[..., 2] ** 2) / v[..., 2] ** 2


def ramp_radiance(grad, n_theta=256):
    """The plane's radiance in closed form (float64), for the bumpmap's slope `grad` = scale * (dh/du, dh/dv):
    dp/du + gu n and dp/dv + gv n give the normal n' ~ (-gu, -gv, 2); the diffuse child reflects
    rho / pi cos' G, cos' = wo . n' where wo lies above both planes, G = 2 / (1 + sqrt(1 + a2 tan^2 theta_o))
    with a2 = min(tan^2 theta_n' / 8, 1) (Conty Estevez et al. 2019, Mitsuba's default use_shadowing_function).
    The light: E cos'(l) G(l); the environment: L times that over the upper hemisphere (midpoint quadrature:
    within 1e-5 of its limit at this size)."""
    n = np.array([-grad[0], -grad[1], 2.0])
    n /= np.linalg.norm(n)

    def reflected(w):
        return np.maximum(w @ n, 0.0) * 2.0 / (1.0 + np.sqrt(1.0 + min(tan2(n) / 8.0, 1.0) * tan2(w)))

    h = 0.5 * np.pi / n_theta
    theta, phi = np.meshgrid((np.arange(n_theta) + 0.5) * h, (np.arange(4 * n_theta) + 0.5) * h, indexing="ij")
    w = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=-1)
    env = (reflected(w) * np.sin(theta)).sum() * h * h
    return RHO / np.pi * (IRRADIANCE * reflected(TO_LIGHT) + RADIANCE * env)


@pytest.mark.plugin("bumpmap", "render")
def test_ramp_height_renders_the_tilted_plane(tmp_path):
    """A diffuse plane under a linear ramp height is a plane of tilted normal: each 4 x 4 block of the image against
    the closed form (ramp_radiance) by a z-test. The light makes the tilt visible (a flat plane, either slope with
    the wrong sign or missing, or the two swapped are 14 % to 76 % off: 7 to 33 block standard errors); the
    environment's share goes through the bumpmap's sampling routine. (Both emitters are picked with probability
    1/2: that is most of the noise.) Checked by hand against Mitsuba 3.9.1 (scalar_rgb, this XML): without the
    environment its image is the closed form to 1e-7 in every pixel, as is ours; with it, at 4096 spp, its mean is
    0.23955 ± 0.0002 where ramp_radiance says 0.23949 (red)."""
    import clrender
    from PIL import Image

    from clrender.testing.stats import compare_block_means_to_value

    Image.fromarray(RAMP.astype(np.uint8), "L").save(tmp_path / "ramp.png")
    fmt = lambda v: ", ".join(f"{float(x)!r}" for x in np.atleast_1d(v))   # noqa: E731
    (tmp_path / "ramp.xml").write_text(RAMP_SCENE.format(
        spp=64, scale=SCALE, rho=fmt(RHO), direction=fmt(-TO_LIGHT), irradiance=IRRADIANCE, radiance=RADIANCE))
    film = clrender.render(clrender.load_scene(tmp_path / "ramp.xml"), seed=1)
    # the bilinear slope of the ramp in uv: 16 and 8 grey levels a texel, 8 texels over uv 0..1
    want = ramp_radiance(SCALE * np.array([16.0 * 8, 8.0 * 8]) / 255.0)
    res = compare_block_means_to_value(film, want, block=4)
    assert res.passed, f"{res.message}: image mean {film.image.reshape(-1, 3).mean(0)}, expected {want}"
