"""Mitsuba 3's bumpmap (a wrapper that turns the shading frame by a height texture's slope:
clrender/bsdfs/bumpmap.py, kernels/bsdfs/bumpmap.h and perturb.h) on the device: eval and pdf against Mitsuba 3.9.1
itself at fixed surface points, a height without slope is exactly its child, chi-square of the wrapped sampling for a
tilted frame with weight == f cos / pdf, and the scene errors (shared set-up: perturbed_common.py; the height
bitmap's gradient is checked in tests/textures/test_bitmap.py)."""
import pytest

from clrender.errors import SceneError
from clrender.testing.plugin_checks import FAMILIES
from clrender.scene.registry import create

from .perturbed_common import DATA, FLAT_CHILDREN, check_tilted_chi2, check_unperturbed_is_the_child, check_values, spec

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
