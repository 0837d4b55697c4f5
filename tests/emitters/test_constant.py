"""Nori's constant environment (clrender/emitters/constant.py, kernels/emitters/constant.h) on the device:
chi-square of its sampled directions against its own pdf, weight == eval / pdf per sample, and a rendered diffuse
plane in it against its albedo times the radiance. (Set-up: emitter_common.py; the environment sum with a sun in
test_distantdisk.py.)"""
import pytest

from clrender.testing.plugin_checks import check_render_value, render_furnace_plane

from .emitter_common import check_chi2_case, check_weight_case


@pytest.mark.plugin("constant", "sampling")
@pytest.mark.parametrize("case", ["constant"])
def test_chi2_emitter_sampling(scenes, case):
    check_chi2_case(scenes, case)


@pytest.mark.parametrize("case", ["constant"])
def test_weight_is_eval_over_pdf(scenes, case):
    check_weight_case(scenes, case)


@pytest.mark.plugin("constant", "render")
def test_furnace_render(tmp_path):
    """A diffuse plane of albedo (0.2, 0.5, 0.9) in a constant environment of radiance 2 (path_mis) shows twice its
    albedo."""
    film = render_furnace_plane(tmp_path, '<bsdf type="diffuse"><color name="albedo" value="0.2, 0.5, 0.9"/></bsdf>',
                                "nori", radiance=2.0)
    check_render_value(film, (0.4, 1.0, 1.8))
