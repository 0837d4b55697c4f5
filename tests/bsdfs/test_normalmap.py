"""Mitsuba 3's normalmap (a wrapper that turns the shading frame: clrender/bsdfs/normalmap.py,
kernels/bsdfs/normalmap.h and perturb.h) on the device: eval and pdf against Mitsuba 3.9.1 itself (with the
composites around it: in a twosided, a blend with a bumpmap, over a bumpmap), a flat map is exactly its child,
chi-square of the wrapped sampling for tilted normals with weight == f cos / pdf, the scene errors, and the
rendered sh_normal AOV against Mitsuba's image (shared set-up: perturbed_common.py)."""
import numpy as np
import pytest

from clrender.errors import SceneError
from clrender.testing.plugin_checks import FAMILIES
from clrender.scene.registry import create

from .perturbed_common import DATA, FLAT_CHILDREN, check_tilted_chi2, check_unperturbed_is_the_child, check_values, spec

#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("normalmap", "bumpmap", "blendbsdf", "conductor", "dielectric", "diffuse", "roughconductor",
               "roughdielectric", "roughplastic", "twosided"), textures=("bitmap",), levels=2)


TILTED = {   # name: (wrapper dict, wi, uv, the normal the wrapper should reflect about, roughly (for the grid))
    "normalmap-roughconductor": ({"type": "normalmap", "normalmap": {"type": "rgb", "value": [0.75, 0.4, 0.85]},
                                  "bsdf": {"type": "roughconductor", "alpha": 0.25, "distribution": "ggx"}},
                                 [0.3, -0.2, 0.9], (0.5, 0.5), 0.25),
    "normalmap-diffuse-grazing": ({"type": "normalmap", "normalmap": {"type": "rgb", "value": [0.9, 0.5, 0.7]},
                                   "bsdf": {"type": "diffuse"}}, [-0.9, 0.1, 0.2], (0.5, 0.5), None),
}


@pytest.mark.plugin("normalmap", "eval")
@pytest.mark.parametrize("name", sorted(n for n in DATA["cases"] if not n.startswith("bumpmap")))
def test_eval_and_pdf_match_mitsuba(ctx, queue, name):
    check_values(ctx, queue, name)


@pytest.mark.parametrize("child", sorted(FLAT_CHILDREN))
def test_an_unperturbed_wrapper_is_its_child(ctx, queue, child, tmp_path):
    check_unperturbed_is_the_child(ctx, queue, child, tmp_path, "normalmap")


@pytest.mark.plugin("normalmap", "sampling")
@pytest.mark.parametrize("name", sorted(TILTED))
def test_chi2_sample_vs_pdf_of_a_tilted_frame(ctx, queue, name):
    check_tilted_chi2(ctx, queue, name, *TILTED[name], n_tests=FAMILIES["perturbed-tilted"])


@pytest.mark.parametrize("d, match", [
    ({"type": "normalmap", "bsdf": {"type": "diffuse"}}, "needs a normal map"),
    ({"type": "normalmap", "normalmap": {"type": "rgb", "value": [0.5, 0.5, 1]}}, "nested <bsdf>"),
], ids=["normalmap-no-map", "normalmap-no-bsdf"])
def test_missing_children_are_errors(d, match):
    with pytest.raises(SceneError, match=match):
        create(spec(d))


def test_nesting_deeper_than_the_dispatch_is_a_located_error():
    from clrender.device import dispatch

    d = {"type": "diffuse"}
    for _ in range(dispatch.BSDF.composite_levels + 1):
        d = {"type": "normalmap", "normalmap": {"type": "rgb", "value": [0.5, 0.5, 1]}, "bsdf": d}
    with pytest.raises(SceneError, match="nested 4 deep; at most 3 levels"):
        create(spec(d))


# ------------------------------------------------------------------------------------------- aov sh_normal
AOV_SCENE = """<scene version="3.0.0">
    <integrator type="aov"><string name="aovs" value="nn:sh_normal"/></integrator>
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="1"/></sampler>
        <film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle">{bsdf}</shape>
</scene>"""
NM = '<bsdf type="normalmap"><rgb name="normalmap" value="0.8, 0.5, 0.9"/><bsdf type="diffuse"/></bsdf>'


@pytest.mark.plugin("normalmap", "render")
@pytest.mark.parametrize("bsdf, want", [
    ('<bsdf type="diffuse"/>', [0, 0, 1]),
    (NM, [0.6, 0, 0.8]),
    (f'<bsdf type="twosided">{NM}</bsdf>', [0, 0, 1]),
], ids=["diffuse", "normalmap", "twosided-normalmap"])
def test_aov_sh_normal_is_the_perturbed_normal(tmp_path, bsdf, want):
    """Mitsuba 3.9.1's aov shows a top-level normalmap's normal as sh_normal (BSDF::sh_frame), not a nested one's:
    these values are what it renders for these scenes."""
    import clrender

    path = tmp_path / "aov.xml"
    path.write_text(AOV_SCENE.format(bsdf=bsdf))
    film = clrender.render(clrender.load_scene(path), seed=1)
    np.testing.assert_allclose(film.image[1:3, 1:3].reshape(-1, 3), np.broadcast_to(want, (4, 3)), atol=1e-5)
