"""The smooth dielectric of Nori and of Mitsuba 3 (one plugin: clrender/bsdfs/dielectric.py,
kernels/bsdfs/dielectric.h) on the device. A delta BSDF, so its sampling is checked exactly rather than by a
chi-square: directions (mirror and Snell), the reflection frequency against Fresnel (a binomial test), weights and
eta, from outside and inside and under total internal reflection; one sample's expected weight; eval and pdf zero;
Mitsuba's events (tests/mitsuba/bsdf_values, written by make_bsdf_values.py); energy; the named indices of
refraction and the scene errors."""
import numpy as np
import pytest
from scipy import stats

from clrender.bsdfs.ior import NAMED_IORS, lookup_ior
from clrender.errors import SceneError
from clrender.testing.plugin_checks import (ALPHA, FURNACE_THETA, bsdf_pdf_eval_batch, bsdf_sample_batch,
                                            check_render_value, fresnel, mean_agrees, mitsuba_bsdf, mitsuba_row,
                                            plugin_row, render_furnace_plane, sidak, wi_at)

from .mitsuba_values import case_id, check_delta_events, ref_cases
from .test_mirror import row_mirror

INT_IOR, EXT_IOR = 1.5046, 1.000277


#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("dielectric", "mirror"), textures=("checkerboard_color",))


def row_dielectric(int_ior=INT_IOR, ext_ior=EXT_IOR):
    return plugin_row(f'<bsdf type="dielectric"><float name="intIOR" value="{int_ior!r}"/>'
                      f'<float name="extIOR" value="{ext_ior!r}"/></bsdf>')


# -------------------------------------------------------------------------------------- Nori's dielectric
DIEL_CASES = [(th, +1) for th in (0.0, 30.0, 60.0, 85.0)] + [(th, -1) for th in (0.0, 20.0, 40.0, 41.0, 45.0,
                                                                                   70.0)]


@pytest.fixture(scope="module")
def dielectric_runs(ctx, queue):
    out = {}
    for th, side in DIEL_CASES:
        wi = wi_at(th) * np.array([1, 1, side])
        out[(th, side)] = (wi, bsdf_sample_batch(ctx, queue, row_dielectric(), wi, 200000, 31))
    return out


@pytest.mark.plugin("dielectric", "sampling")
def test_dielectric_frequencies_and_weights(dielectric_runs):
    a = sidak(ALPHA, 2 * len(DIEL_CASES))
    for (th, side), (wi, s) in dielectric_runs.items():
        wi32 = (wi / np.linalg.norm(wi)).astype(np.float32)
        F = float(fresnel(wi[2], EXT_IOR, INT_IOR))
        assert np.all(s.measure == 1)
        refl = s.wo[:, 2] * wi[2] > 0
        eta_i, eta_t = (EXT_IOR, INT_IOR) if side > 0 else (INT_IOR, EXT_IOR)
        k = int(refl.sum())
        n = len(refl)
        if F >= 1:
            assert k == n, "total internal reflection must always reflect"
        else:
            p = stats.binomtest(k, n, F).pvalue
            assert p > a, f"theta {th} side {side}: reflected {k / n:.5f}, Fresnel {F:.5f} (p={p:.3g})"
        # reflection: exact mirror, weight 1, eta 1
        np.testing.assert_allclose(s.wo[refl], np.broadcast_to(wi32 * np.array([-1, -1, 1]), s.wo[refl].shape),
                                   atol=1e-7)
        assert np.all(s.weight[refl] == 1) and np.all(s.eta[refl] == 1)
        # refraction: Snell, opposite azimuth, other side, unit length, weight (eta_i/eta_t)^2
        t = ~refl
        if t.any():
            wo = s.wo[t].astype(np.float64)
            np.testing.assert_allclose(np.linalg.norm(wo, axis=1), 1, atol=1e-6)
            sin_i = np.hypot(wi[0], wi[1])
            np.testing.assert_allclose(eta_t * np.hypot(wo[:, 0], wo[:, 1]), eta_i * sin_i, atol=2e-6)
            if sin_i > 0:
                assert np.all(wo[:, 0] * wi[0] <= 0)
            assert np.all(np.sign(wo[:, 2]) == -side)
            np.testing.assert_allclose(s.weight[t], (eta_i / eta_t) ** 2, rtol=1e-6)
            np.testing.assert_allclose(s.eta[t], eta_t / eta_i, rtol=1e-6)


def test_dielectric_expected_weight(dielectric_runs):
    """One sample's expected weight at normal incidence: F + (1-F)(eta_i/eta_t)^2, from outside and inside."""
    a = sidak(ALPHA, 2)
    for side in (+1, -1):
        wi, s = dielectric_runs[(0.0, side)]
        F = float(fresnel(side * 1.0, EXT_IOR, INT_IOR))
        ratio = EXT_IOR / INT_IOR if side > 0 else INT_IOR / EXT_IOR
        expect = F + (1 - F) * ratio**2
        w = s.weight[:, 0].astype(np.float64)
        ok, p = mean_agrees(w, expect, a, rel=0)
        assert ok, f"side {side}: mean {w.mean():.5f} vs {expect:.5f}"


def test_delta_eval_pdf_zero(ctx, queue):
    """eval and pdf of the delta BSDFs are zero everywhere (the mirror's checked here beside the dielectric's)."""
    wo = np.array([[0, 0, 1], [0, 0, -1], [0.6, 0, 0.8]])
    for row in (row_mirror(), row_dielectric()):
        pdf, f = bsdf_pdf_eval_batch(ctx, queue, row, (0, 0, 1), wo)
        assert np.all(pdf == 0) and np.all(f == 0)


# ----------------------------------------------------------------------------------- Mitsuba's dielectric
DELTA_REFS = ref_cases(("dielectric",))


@pytest.mark.plugin("dielectric", "sampling")
@pytest.mark.parametrize("case", DELTA_REFS, ids=[case_id(c) for c in DELTA_REFS])
def test_delta_events_match_mitsuba(ctx, queue, case):
    check_delta_events(ctx, queue, case)


def test_white_furnace(ctx, queue):
    """The smooth dielectric's reflected plus transmitted importance (weight · eta² for refractions) is exactly what
    arrives, from either side."""
    for wi in (wi_at(0.0), wi_at(70.0), wi_at(30.0, -1), wi_at(60.0, -1)):
        s = bsdf_sample_batch(ctx, queue, mitsuba_row("dielectric"), wi, 20000, 43)
        np.testing.assert_allclose(s.weight[:, 0] * s.eta ** 2, 1.0, rtol=1e-5)


def test_named_iors():
    assert lookup_ior("BK7") == 1.5046 and lookup_ior("diamond") == 2.419 and lookup_ior("Water Ice") == 1.31
    assert len(NAMED_IORS) == 23
    b = mitsuba_bsdf("dielectric", int_ior="diamond", ext_ior="water")
    assert (b.int_ior, b.ext_ior) == (2.419, 1.333)
    b = mitsuba_bsdf("roughdielectric")
    assert (b.int_ior, b.ext_ior) == (1.5046, 1.000277)
    with pytest.raises(SceneError, match="unknown index of refraction name 'glas'.*bk7"):
        mitsuba_bsdf("dielectric", int_ior="glas")


@pytest.mark.parametrize("kind,kw,message", [
    ("dielectric", dict(specular_reflectance=(-1.0, 0.0, 0.0)), "specular_reflectance must be non-negative"),
])
def test_scene_errors(kind, kw, message):
    with pytest.raises(SceneError, match=message):
        mitsuba_bsdf(kind, **kw)


# ------------------------------------------------------------------------------------------- render
@pytest.mark.plugin("dielectric", "render")
# one render in the default run (each builds its own program: seconds), both with the slow suites
@pytest.mark.parametrize("fmt", ["nori", pytest.param("mitsuba", marks=pytest.mark.slow)])
def test_furnace_render(tmp_path, fmt):
    """A glass plane (one interface) in a constant environment of radiance 1 (path_mis, Mitsuba's path): the
    reflected environment F and the one below, refracted into the camera, (1 - F) (eta_ext / eta_int)^2."""
    xml = ('<bsdf type="dielectric"/>' if fmt == "mitsuba" else
           f'<bsdf type="dielectric"><float name="intIOR" value="{INT_IOR!r}"/>'
           f'<float name="extIOR" value="{EXT_IOR!r}"/></bsdf>')
    F = float(fresnel(np.cos(np.radians(FURNACE_THETA)), EXT_IOR, INT_IOR))
    check_render_value(render_furnace_plane(tmp_path, xml, fmt), F + (1 - F) * (EXT_IOR / INT_IOR) ** 2)
