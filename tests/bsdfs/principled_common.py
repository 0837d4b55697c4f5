"""What the test files of Mitsuba 3's principled and principledthin share: the plugins from Mitsuba dicts, the
integration grid around their lobes, and the checks against Mitsuba 3's own values (tests/mitsuba/bsdf_values/
principled.json and principledthin.json, written by make_principled_values.py in that folder)."""
import functools
import json
from pathlib import Path

import numpy as np
from scipy import stats

from clrender.device import layout
from clrender.device.dispatch import flag_defines
from clrender.scene.registry import create
from clrender.testing.directions import refracted, wi_at
from clrender.testing.mitsuba_dict import spec_from_dict
from clrender.testing.plugin_checks import (ALPHA, CHECKER_VALUES, RES, SUB, UV1, UV2, bsdf_pdf_eval_batch,
                                            bsdf_sample_batch, check_sample_weights, mitsuba_bsdf_with_checkers,
                                            refined_direction_grid, sidak)
from clrender.textures.texture import TextureTable

VALUES = Path(__file__).resolve().parent.parent / "mitsuba" / "bsdf_values"
VALUE_FILES = ("principled.json", "principledthin.json")


def make(kind="principled", **kw):
    """The plugin as a Mitsuba file (here: a Mitsuba dict) gives it; colours are tuples."""
    d = {"type": kind}
    for k, v in kw.items():
        d[k] = {"type": "rgb", "value": list(v)} if isinstance(v, tuple) else v
    return create(spec_from_dict(d))


def _alphas(b):
    """The roughnesses of the lobes, for refining the integration grid around their peaks."""
    out = []
    r = b.floats["roughness"][0]
    aspect = np.sqrt(1 - 0.9 * b.floats["anisotropic"][0])
    thin = "diff_trans" in b.floats
    for s in ((1.0, 0.65 * b.floats["eta"][0] - 0.35) if thin else (1.0,)):
        r2 = (s * r) ** 2
        out += [max(1e-3, r2 / aspect), max(1e-3, r2 * aspect)]
    if b.floats.get("clearcoat", (0,))[0] > 0:
        out.append(0.1 + b.floats["clearcoat_gloss"][0] * (0.001 - 0.1))
    return out


def transmits(b):
    return b.floats["spec_trans"][0] > 0 or b.floats.get("diff_trans", (0,))[0] > 0


def grid_for(b, wi):
    """Integration points refined around the peaks (the mirror direction and the refracted one) at the lobes'
    widths and their widths across the plane of incidence."""
    peaks = []
    targets = [wi * np.array([-1, -1, 1])]
    t = -wi if "diff_trans" in b.floats else refracted(wi, b.eta)   # a thin sheet does not bend light
    if t is not None and transmits(b):
        targets.append(t)
    for a in _alphas(b):
        if a >= 0.6:
            continue
        for d in targets:
            peaks += [(d, min(14 * a, np.pi)), (d, 14 * a * max(abs(wi[2]), 0.03)), (d, 1.2 * a)]
    # at most 4 M points: rates-70's 18 wide peaks made 18.9 M (54 s of pdf evaluations for one case); at 3.3 M
    # its expected counts moved by at most 0.18 % (sum of squared change / expected 0.005, against a chi-square
    # of about 200 dof), and every other case stays under the cap unchanged
    return refined_direction_grid(RES, SUB, peaks, n_fine=300, max_points=4_000_000)


def chi2_case_of(cases):
    """`chi2_case` over `cases` {name: (make's keywords, wi)}."""
    def chi2_case(name):
        kw, wi = cases[name]
        b = make(**kw)
        return b.pack(), wi, grid_for(b, wi)

    return chi2_case


def check_weights(cases, run, name):
    """weight == f cos / pdf; a transmitting case samples transmissions too, with the event's eta (a thin sheet
    does not refract: 1)."""
    b = make(**cases[name][0])
    s, keep, wi = run.samples, run.keep, run.wi
    refl = check_sample_weights(s, keep, wi)
    if transmits(b):
        assert (~refl).any(), f"{name}: no transmission sampled"
        eta = 1.0 if "diff_trans" in b.floats else b.eta if wi[2] > 0 else 1 / b.eta   # thin: no refraction
        np.testing.assert_allclose(s.eta[keep][~refl], eta, rtol=1e-6)
    else:
        assert refl.all()


# ----------------------------------------------------------------------------------- against Mitsuba
@functools.lru_cache(maxsize=None)
def values(fname="principled.json"):
    return json.loads((VALUES / fname).read_text())


def value_cases(fname):
    return list(values(fname)["cases"])


def rows_of(d):
    b = create(spec_from_dict(d))
    table = TextureTable()
    return np.array(b.pack_rows(table), layout.dtype("Bsdf")), table.array()


def check_eval_and_pdf(ctx, queue, fname, name):
    """Mitsuba's eval (f |cos_o|) and pdf at 292 direction pairs per case. float32 against Mitsuba's float32 in
    another order of operations: the largest difference measured is 2.6e-4 relative for principled (GGX alpha
    0.0025 and GTR1 alpha 0.011, where D changes fastest), 1.2e-6 for principledthin; 2e-3 leaves room for
    compilers, and is far below what a wrong term makes (the weakest lobe here, sheen at spec_trans 1, shifts
    values by 0.02-2 %)."""
    data = values(fname)
    case = data["cases"][name]
    wi, wo = np.array(data["wi"]), np.array(data["wo"])
    rows, tex = rows_of(case["dict"])
    pdf, f = bsdf_pdf_eval_batch(ctx, queue, rows, wi, wo, textures=tex)
    got, ref, ref_pdf = f * np.abs(wo[:, 2:3]), np.array(case["eval"]), np.array(case["pdf"])
    assert (ref > 0).any(1).sum() > 80, "the reference set must exercise the lobes"
    close = np.abs(got - ref) <= 1e-7 + 2e-3 * np.abs(ref)
    bad = np.nonzero(~close.all(1))[0]
    assert close.all(), f"eval differs from Mitsuba's at pairs {bad.tolist()}: {got[bad][:3].tolist()} vs " \
                        f"{ref[bad][:3].tolist()}"
    close = np.abs(pdf - ref_pdf) <= 1e-7 + 2e-3 * np.abs(ref_pdf)
    bad = np.nonzero(~close)[0]
    assert close.all(), f"pdf differs from Mitsuba's at pairs {bad.tolist()}: {pdf[bad][:3]} vs {ref_pdf[bad][:3]}"


def check_albedo(ctx, queue, fname, name):
    """The mean sample weight (the albedo, radiance transport) at four incident directions against Mitsuba's own
    sample() over 2^18 samples: a z-test of the difference against both standard errors, Šidák-corrected over all
    cases (of both files) and directions. This checks the sampling routine's weights as a whole, where eval and
    pdf check its parts."""
    data = values(fname)
    case = data["cases"][name]
    rows, tex = rows_of(case["dict"])
    n = 1 << 17
    a_t = sidak(ALPHA, 4 * sum(len(values(f)["cases"]) for f in VALUE_FILES))
    for (th, side), (ref, ref_se) in zip(data["albedo_wi"], case["albedo"]):
        s = bsdf_sample_batch(ctx, queue, rows, wi_at(th, side), n, 29, textures=tex)
        w = s.weight[:, 0].astype(np.float64)
        se = np.hypot(w.std() / np.sqrt(n), ref_se)
        if se < 1e-6:   # a constant weight (a Lambertian lobe alone, or nothing)
            assert abs(w.mean() - ref) <= 1e-5 * max(1.0, abs(ref)), f"{name} at {th} deg ({side}): {w.mean()} vs {ref}"
            continue
        p = 2 * stats.norm.sf(abs(w.mean() - ref) / se)
        assert p > a_t, f"{name} at {th} deg ({side}): albedo {w.mean():.5f} vs Mitsuba's {ref:.5f} +- {ref_se:.5f}"


# ---------------------------------------------------------------------------------------------- textures
def check_textured(ctx, queue, kind, names):
    """Every texturable parameter in `names`, textured, equals the constant BSDF with the texture's value there: a
    float reads the texture's first channel (0.2 where the checkerboard shows value1, 0.7 elsewhere), base_color
    the colour."""
    rng = np.random.default_rng(4)
    wi = np.array([0.3, 0.2, 0.93])
    wo = rng.normal(size=(600, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    for name in names:
        # the lobes the parameter modulates are on
        extra = dict(spec_trans=0.4) if name != "spec_trans" else {}
        if name == "sheen_tint":
            extra["sheen"] = 0.8
        if name == "clearcoat_gloss":
            extra["clearcoat"] = 1.0
        if name == "spec_tint" and kind == "principled":
            extra["metallic"] = 0.2
        if kind == "principledthin" and name != "diff_trans":
            extra["diff_trans"] = 0.5
        b = mitsuba_bsdf_with_checkers(kind, (name,), **extra)
        r = b.pack()
        assert r["flags"] & flag_defines()["BSDF_UV"]
        for uv, v, c in ((UV1, 0.2, CHECKER_VALUES[0]), (UV2, 0.7, CHECKER_VALUES[1])):
            ref = make(kind, **extra, **{name: c if name == "base_color" else v}).pack()
            p1, f1 = bsdf_pdf_eval_batch(ctx, queue, r, wi, wo, uv=uv, textures=b.textures_table)
            p2, f2 = bsdf_pdf_eval_batch(ctx, queue, ref, wi, wo, uv=uv)
            assert f2.max() > 0
            np.testing.assert_allclose(f1, f2, rtol=1e-5, atol=1e-7, err_msg=f"{kind} {name}")
            np.testing.assert_allclose(p1, p2, rtol=1e-5, atol=1e-7, err_msg=f"{kind} {name}")
