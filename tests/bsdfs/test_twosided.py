"""Mitsuba 3's twosided (a composite: clrender/bsdfs/twosided.py, kernels/bsdfs/twosided.h) on the device:
chi-square of its sampling against its own pdf from the front and the back (each side its own child), weight ==
f cos/pdf for smooth samples and the coating's delta samples, eval against Mitsuba 3's own values, a furnace render
from below, and the located error of a transmitting child. (principled's file checks which of its children it
refuses.)

All chi-square cases share one Šidák correction (N_CHI2 tests at overall level ALPHA)."""
import pytest

from clrender.errors import SceneError
from clrender.scene.registry import create
from clrender.testing.mitsuba_dict import spec_from_dict
from clrender.testing.plugin_checks import (FAMILIES, check_render_value, render_furnace_plane)

from .coated_common import CHI2_SEED  # noqa: F401 (read by conftest.py's chi2_runs)
from .coated_common import (check_smooth_pdf_integral, check_values, check_weights, chi2_case_of, value_cases)

#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("twosided", "mask", "diffuse", "plastic", "roughplastic"), levels=2)


ROUGH = {"type": "roughplastic", "alpha": 0.2, "distribution": "ggx"}
CASES = [
    ("twosided-front-45", {"type": "twosided", "a": ROUGH, "b": {"type": "plastic"}}, 45.0, False, 0.2),
    ("twosided-back-45", {"type": "twosided", "a": {"type": "plastic"}, "b": ROUGH}, 45.0, True, 0.2),
]
N_CHI2 = FAMILIES["coated-chi2"]
chi2_case = chi2_case_of(CASES)


@pytest.mark.plugin("twosided", "sampling")
@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_chi2_sample_vs_pdf(chi2_runs, name):
    chi2_runs.check(name)


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_weights(chi2_runs, name):
    check_weights(chi2_runs[name])


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_pdf_integral(chi2_runs, name):
    check_smooth_pdf_integral(chi2_runs[name], name)


@pytest.mark.parametrize("d,match", [
    ({"type": "twosided", "a": {"type": "mask", "a": {"type": "plastic"}}}, "transmits light"),
])
def test_errors(d, match):
    with pytest.raises(SceneError, match=match):
        create(spec_from_dict(d))


@pytest.mark.plugin("twosided", "eval")
@pytest.mark.parametrize("data,case", value_cases("twosided"))
def test_eval_and_pdf_match_mitsuba(ctx, queue, data, case):
    check_values(ctx, queue, data, case)


@pytest.mark.plugin("twosided", "render")
def test_furnace_render(tmp_path):
    """A twosided plane, diffuse 0.2 in front and 0.7 behind, seen from below (the camera 140 degrees from the
    front's normal) in a constant environment of radiance 1 (Mitsuba's path), shows the back's 0.7."""
    xml = ('<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.2"/></bsdf>'
           '<bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></bsdf>')
    check_render_value(render_furnace_plane(tmp_path, xml, theta=140.0), 0.7)
