"""Mitsuba 3's roughplastic (clrender/bsdfs/roughplastic.py, kernels/bsdfs/roughplastic.h) on the device: chi-square
of its sampling against its own pdf (angles, roughness, Beckmann and GGX, visible normals or not, IORs), weight ==
f cos/pdf, the pdf's integral, energy (sampling mean == quadrature of eval), its T(mu) table as a scene row, eval
against Mitsuba 3's own values, a furnace render, the located errors, and checks that the chi-square catches a wrong
pdf.

All chi-square cases share one Šidák correction (N_CHI2 tests at overall level ALPHA)."""
import numpy as np
import pytest

from clrender.errors import SceneError
from clrender.scene.registry import create
from clrender.testing.mitsuba_dict import spec_from_dict
from clrender.testing.plugin_checks import (ALPHA, FAMILIES, FURNACE_THETA, bsdf_chi2, bsdf_pdf_eval_batch,
                                            check_render_value, chi2_test, lobe_grid, render_furnace_plane)

from .coated_common import (CHI2_SEED, albedo_quadrature, check_energy, check_smooth_pdf_integral, check_values,
                            check_weights, chi2_case_of, rgb, rows_of, value_cases, wi_at)


#: the file's one test program (tests/bsdfs/conftest.py one_program)
PROGRAM = dict(bsdfs=("roughplastic", "blendbsdf"), textures=("checkerboard_color",), levels=1)


def _cases():
    c = []
    for alpha in (0.05, 0.3, 0.8):
        for th in (0.0, 60.0, 85.0):
            c.append((f"rough-beckmann-a{alpha:g}-{th:g}", {"type": "roughplastic", "alpha": alpha}, th, False,
                      alpha))
    for alpha in (0.05, 0.3):
        for vis in (True, False):
            for th in (30.0, 85.0):
                c.append((f"rough-ggx-a{alpha:g}-{'vis' if vis else 'all'}-{th:g}",
                          {"type": "roughplastic", "distribution": "ggx", "alpha": alpha, "sample_visible": vis,
                           "int_ior": 1.8, "diffuse_reflectance": rgb(0.1, 0.2, 0.3)}, th, False, alpha))
    return c


CASES = _cases()
N_CHI2 = FAMILIES["coated-chi2"]
chi2_case = chi2_case_of(CASES)


@pytest.mark.plugin("roughplastic", "sampling")
@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_chi2_sample_vs_pdf(chi2_runs, name):
    chi2_runs.check(name)


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_weights(chi2_runs, name):
    check_weights(chi2_runs[name])


@pytest.mark.parametrize("name", [c[0] for c in CASES])
def test_pdf_integral(chi2_runs, name):
    check_smooth_pdf_integral(chi2_runs[name], name)


def test_roughplastic_tables_are_scene_rows(ctx, queue):
    """A roughplastic's T(mu) is a row of the scene's bsdf_tables, stored once for equal parameters; a blend of two
    roughplastics evaluates each with its own row (the weighted sum of the two alone)."""
    from clrender.textures.texture import TextureTable

    table = TextureTable()
    made = [create(spec_from_dict({"type": "roughplastic", "alpha": a})) for a in (0.3, 0.3, 0.6)]
    rows = [b.pack(table) for b in made]
    assert [int(r["roughplastic"]["table"]) for r in rows] == [0, 0, 1]
    np.testing.assert_array_equal(table.bsdf_tables_array()["values"], np.float32([made[0].trans, made[2].trans]))

    wi = wi_at(70.0)   # a grazing wi, where the two T(mu) differ most
    wo = np.array([[0.3, 0.2, 0.9], [-0.5, 0.1, 0.6], [0.8, -0.1, 0.2]])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    a, b = {"type": "roughplastic", "alpha": 0.3}, {"type": "roughplastic", "alpha": 0.6, "int_ior": 1.8}
    blend = rows_of({"type": "blendbsdf", "weight": 0.25, "a": a, "b": b})
    assert len(blend.tables) == 2
    pa, fa = bsdf_pdf_eval_batch(ctx, queue, rows_of(a), wi, wo)
    pb, fb = bsdf_pdf_eval_batch(ctx, queue, rows_of(b), wi, wo)
    pm, fm = bsdf_pdf_eval_batch(ctx, queue, blend, wi, wo)
    np.testing.assert_allclose(fm, 0.75 * fa + 0.25 * fb, rtol=1e-5)
    np.testing.assert_allclose(pm, 0.75 * pa + 0.25 * pb, rtol=1e-5)


ENERGY = [
    ("rough-beckmann-white", {"type": "roughplastic", "alpha": 0.4, "diffuse_reflectance": rgb(1, 1, 1)}),
    ("rough-ggx-white", {"type": "roughplastic", "alpha": 0.4, "distribution": "ggx",
                         "diffuse_reflectance": rgb(1, 1, 1)}),
]


@pytest.mark.parametrize("name,d", ENERGY, ids=[e[0] for e in ENERGY])
def test_energy(ctx, queue, name, d):
    check_energy(ctx, queue, d)


def test_chi2_catches_a_wrong_pdf(ctx, queue):
    """A roughplastic pdf of another alpha fails the chi-square test."""
    wi = wi_at(30.0)
    rows = rows_of({"type": "roughplastic", "alpha": 0.3})
    other = rows_of({"type": "roughplastic", "alpha": 0.33})
    _, _, obs, exp = bsdf_chi2(ctx, queue, rows, wi, lobe_grid(wi, 0.3), seed=CHI2_SEED,
                               pdf_fn=lambda dirs: bsdf_pdf_eval_batch(ctx, queue, other, wi, dirs)[0])
    assert not chi2_test(obs, exp, alpha=ALPHA, n_tests=N_CHI2).passed


@pytest.mark.parametrize("d,match", [
    ({"type": "roughplastic", "distribution": "phong"}, "distribution must be one of beckmann, ggx"),
    ({"type": "roughplastic", "alpha_u": 0.1}, "anisotropic"),
])
def test_errors(d, match):
    with pytest.raises(SceneError, match=match):
        create(spec_from_dict(d))


@pytest.mark.plugin("roughplastic", "eval")
@pytest.mark.parametrize("data,case", value_cases("roughplastic"))
def test_eval_and_pdf_match_mitsuba(ctx, queue, data, case):
    check_values(ctx, queue, data, case)


@pytest.mark.plugin("roughplastic", "render")
def test_furnace_render(ctx, queue, tmp_path):
    """A roughplastic plane in a constant environment of radiance 1 (Mitsuba's path) shows its directional albedo,
    the quadrature of its eval (to 0.3 %)."""
    d = {"type": "roughplastic", "alpha": 0.3, "diffuse_reflectance": rgb(0.2, 0.5, 0.8)}
    xml = ('<bsdf type="roughplastic"><float name="alpha" value="0.3"/>'
           '<rgb name="diffuse_reflectance" value="0.2, 0.5, 0.8"/></bsdf>')
    ref = albedo_quadrature(ctx, queue, rows_of(d), wi_at(FURNACE_THETA))
    check_render_value(render_furnace_plane(tmp_path, xml), ref, rel_tol=3e-3)
