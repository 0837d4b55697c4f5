"""Mitsuba 3's conductor (a smooth metal: clrender/bsdfs/conductor.py, kernels/bsdfs/conductor.h) on the device: a
delta BSDF, so its sampled events (direction, weight, eta) are checked against Mitsuba 3's own (tests/mitsuba/
bsdf_values, written by make_bsdf_values.py) rather than by a chi-square; the material presets, a textured
reflectance and the scene errors."""
import numpy as np
import pytest

from clrender.bsdfs.conductor import MATERIALS
from clrender.errors import SceneError
from clrender.testing.plugin_checks import (UV2, bsdf_sample_batch, check_render_value, mitsuba_bsdf,
                                            mitsuba_bsdf_with_checkers, mitsuba_row, render_furnace_plane, wi_at)

from .mitsuba_values import case_id, check_delta_events, ref_cases

make, row = mitsuba_bsdf, mitsuba_row
#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("conductor",), textures=("checkerboard_color",))


DELTA_REFS = ref_cases(("conductor",))


@pytest.mark.plugin("conductor", "sampling")
@pytest.mark.parametrize("case", DELTA_REFS, ids=[case_id(c) for c in DELTA_REFS])
def test_delta_events_match_mitsuba(ctx, queue, case):
    check_delta_events(ctx, queue, case)


def test_conductor_presets_and_defaults(ctx, queue):
    """material none (the default) is a perfect mirror; presets give Mitsuba's RGB Fresnel at normal incidence."""
    s = bsdf_sample_batch(ctx, queue, row("conductor"), wi_at(40.0), 1000, 1)
    np.testing.assert_allclose(s.weight, 1.0, rtol=1e-6)
    s = bsdf_sample_batch(ctx, queue, row("conductor", material="Au"), wi_at(0.0), 10, 1)
    eta, k = (np.array(x) for x in MATERIALS["Au"])
    F0 = ((eta - 1) ** 2 + k ** 2) / ((eta + 1) ** 2 + k ** 2)
    np.testing.assert_allclose(s.weight[0], F0, rtol=1e-5)
    s = bsdf_sample_batch(ctx, queue, row("conductor", material="Au"), wi_at(30.0, -1), 10, 1)
    assert np.all(s.weight == 0), "one-sided: nothing from below"
    assert {"Au", "Ag", "Al", "Cu", "a-C", "W", "Cr"} <= set(MATERIALS)


def test_textured_parameters(ctx, queue):
    """A textured specular_reflectance scales the mirror's weight by the texture."""
    b = mitsuba_bsdf_with_checkers("conductor", ("specular_reflectance",))
    s = bsdf_sample_batch(ctx, queue, b.pack(), wi_at(20.0), 2, 1, uv=UV2, textures=b.textures_table)
    np.testing.assert_allclose(s.weight, [[0.7, 0.5, 0.3]] * 2, rtol=1e-6)


@pytest.mark.parametrize("kind,kw,message", [
    ("conductor", dict(material="Gold"), "unknown conductor material 'Gold'; known: none, a-C"),
    ("conductor", dict(material="Au", eta=(1.0, 1.0, 1.0)), "either material or eta and k"),
])
def test_scene_errors(kind, kw, message):
    with pytest.raises(SceneError, match=message):
        make(kind, **kw)


@pytest.mark.plugin("conductor", "render")
def test_furnace_render(tmp_path):
    """A perfect mirror (material none) scaled by specular_reflectance in a constant environment of radiance 1
    (Mitsuba's path) reflects exactly that reflectance."""
    xml = '<bsdf type="conductor"><rgb name="specular_reflectance" value="0.3, 0.6, 0.9"/></bsdf>'
    check_render_value(render_furnace_plane(tmp_path, xml), (0.3, 0.6, 0.9))
