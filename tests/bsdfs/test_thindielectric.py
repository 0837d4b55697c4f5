"""Mitsuba 3's thindielectric (a thin sheet: clrender/bsdfs/thindielectric.py, kernels/bsdfs/thindielectric.h) on
the device: a delta BSDF, so its sampled events (direction, weight, eta, frequency) are checked against Mitsuba 3's
own (tests/mitsuba/bsdf_values, written by make_bsdf_values.py) rather than by a chi-square; energy (it returns
exactly what arrives) and the scene errors."""
import numpy as np
import pytest

from clrender.errors import SceneError
from clrender.testing.plugin_checks import (bsdf_sample_batch, check_render_value, mitsuba_bsdf, mitsuba_row,
                                            render_furnace_plane, wi_at)

from .mitsuba_values import case_id, check_delta_events, ref_cases

DELTA_REFS = ref_cases(("thindielectric",))


@pytest.mark.plugin("thindielectric", "sampling")
@pytest.mark.parametrize("case", DELTA_REFS, ids=[case_id(c) for c in DELTA_REFS])
def test_delta_events_match_mitsuba(ctx, queue, case):
    check_delta_events(ctx, queue, case)


def test_white_furnace(ctx, queue):
    """The thin sheet returns exactly what arrives, from either side."""
    for wi in (wi_at(0.0), wi_at(70.0), wi_at(30.0, -1), wi_at(60.0, -1)):
        s = bsdf_sample_batch(ctx, queue, mitsuba_row("thindielectric"), wi, 20000, 43)
        np.testing.assert_allclose(s.weight[:, 0] * s.eta ** 2, 1.0, rtol=1e-5)


@pytest.mark.parametrize("kind,kw,message", [
    ("thindielectric", dict(int_ior=-1.0), "int_ior must be positive"),
])
def test_scene_errors(kind, kw, message):
    with pytest.raises(SceneError, match=message):
        mitsuba_bsdf(kind, **kw)


@pytest.mark.plugin("thindielectric", "render")
def test_furnace_render(tmp_path):
    """A thin sheet in a constant environment of radiance 1 (Mitsuba's path): what it reflects and what it lets
    through, unbent, add up to exactly 1."""
    check_render_value(render_furnace_plane(tmp_path, '<bsdf type="thindielectric"/>'), 1.0)
