"""The checks every plugin's tests run, one set per kind, parametrised by the plugin (from XML or a Mitsuba dict).

A BSDF plugin's test file (tests/bsdfs/test_<name>.py) states its cases (the plugin, wi, the lobe widths) and runs:

- `bsdf_chi2`: samples on the device binned over Nori's (RES cos theta x 2 RES phi) cells against the integral of
  the plugin's own pdf over them (`lobe_grid` refines the quadrature around the specular peaks), then
  `chi2.chi2_test` with a Šidák correction over its family (`BsdfRuns` computes each case once, when a test
  first asks for it);
- `chi2.check_pdf_integral`: the pdf integrates to the fraction of samples that survive (at most 1);
- `check_weights` / `chi2.check_sample_weights` / `check_mixed_weights`: every kept sample's weight is f cos / pdf
  (and a delta lobe's samples go where they must);
- `mean_agrees` / `mean_le`: energy, a white furnace (the mean weight against a reference or a bound);
- `fresnel`: the dielectric Fresnel reflectance in float64, the reference several plugins are checked against;
- `render_furnace_plane` + `check_render_value`: its render test, a plane of it in a constant environment, whose
  image is its directional albedo (a closed form, or `albedo_quadrature` of its eval).

Rows are always built by the plugins themselves (`bsdf_from_xml`, `mitsuba_bsdf`), never by hand. A filter's file
(tests/filters/) runs `check_filter_offsets` (chi-square against its own table), `check_filter_weights` and
`check_filter_edge_render`; a texture's (tests/textures/) `texture_eval_batch` against its host eval and
`check_texture_render`. The Šidák families of the statistical tests are FAMILIES.

Tests declare which plugin and which aspect they cover with the `plugin` marker (registered in tests/conftest.py):
``@pytest.mark.plugin("roughplastic", "sampling")``; tests/test_plugin_coverage.py reads these markers to check
that every registered plugin has its test file, a sampling (or, for textures, evaluation) test and a render test.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .chi2 import (bin_directions, check_pdf_integral, check_sample_weights, chi2_test,  # noqa: F401 (re-exported)
                   expected_from_grid, refined_direction_grid, sidak)
from .kernels import bsdf_pdf_eval_batch, bsdf_sample_batch, pack_rows  # noqa: F401 (re-exported)

ALPHA = 0.01                  # overall significance level of a test file's family of statistical tests
RES = 10                      # Nori's chi2test: 10 cos(theta) bins x 20 phi bins
N_SAMPLES = 5000 * RES * RES  # Nori/Mitsuba use 5000 res^2 samples (Nori's default doubles it)
SUB = 8                       # midpoint sub-cells per cell and axis (plus refinement around peaks)

#: How many tests each family of statistical tests is Šidák-corrected over: the families of the theme modules the
#: per-plugin test files were split from (issue 26), so that every threshold stays what it was. A new plugin's file
#: corrects over its own cases.
FAMILIES = {
    "nori-bsdf-chi2": 53,          # diffuse 5 + microfacet 48 (tests/test_bsdfs.py)
    "mitsuba-rough-chi2": 60,      # roughconductor 30 + roughdielectric 30 (tests/test_mitsuba_bsdfs.py)
    "mitsuba-rough-furnace": 54,   # roughconductor 18 + roughdielectric 36
    "coated-chi2": 26,             # plastic 4, roughplastic 17, blendbsdf 1, mask 2, twosided 2 (test_coated_bsdfs.py)
    "coated-energy": 6,            # plastic 2, roughplastic 2, blendbsdf 1, mask 1
    "principled-chi2": 16,         # principled 12 + principledthin 4 (tests/test_mitsuba_principled.py)
    "principled-furnace": 27,      # principled 21 + principledthin 6
    "perturbed-tilted": 3,         # normalmap 2 + bumpmap 1 (tests/test_mitsuba_perturbed.py)
    "filters": 5,                  # box 2, tent, gaussian, mitchell (tests/test_filters.py); catmullrom and lanczos,
}                                  # tested since, at the same level

#: what a test may declare it covers (the `plugin` marker's second argument)
ASPECTS = ("sampling", "eval", "render")


# ------------------------------------------------------------------------------------------ plugins
def bsdf_from_xml(xml: str, filename: str = "row.xml"):
    """The first BSDF of a Nori XML fragment (wrapped in <scene> unless it is a whole scene), as the loader makes it."""
    from .. import plugins  # noqa: F401
    from ..scene.registry import create
    from ..scene.xmlparser import parse_string

    text = xml if xml.lstrip().startswith("<scene") else f"<scene>{xml}</scene>"
    spec = parse_string(text, filename)
    return create(next(s for s in spec.walk() if s.tag == "bsdf"))


def plugin_row(xml: str):
    """The packed row of the first BSDF of a Nori XML fragment."""
    return bsdf_from_xml(xml).pack()


def mitsuba_props(**kw) -> dict:
    """{name: (property tag, value)} from Python values: str -> string, bool -> boolean, tuple -> color, else float."""
    out = {}
    for k, v in kw.items():
        if isinstance(v, str):
            out[k] = ("string", v)
        elif isinstance(v, bool):
            out[k] = ("boolean", v)
        elif isinstance(v, tuple):
            out[k] = ("color", v)
        else:
            out[k] = ("float", float(v))
    return out


def mitsuba_bsdf(kind: str, props: dict | None = None, **kw):
    """The BSDF as a Mitsuba file would give it: `props` ({name: (tag, value)}) or keywords (`mitsuba_props`)."""
    from .. import plugins  # noqa: F401
    from ..scene.registry import instantiate

    return instantiate("bsdf", kind, props if props is not None else mitsuba_props(**kw), fmt="mitsuba")


def mitsuba_row(kind: str, **kw):
    return mitsuba_bsdf(kind, **kw).pack()


def wi_at(theta_deg: float, side: int = 1) -> np.ndarray:
    """The direction at polar angle theta (degrees) in the xz plane, above (side +1) or below (-1) the surface."""
    t = np.radians(theta_deg)
    return np.array([np.sin(t), 0.0, side * np.cos(t)])


def refracted(wi, eta_ext, eta_int):
    """The macro-surface refraction direction of wi (None under total internal reflection)."""
    ei, et = (eta_ext, eta_int) if wi[2] > 0 else (eta_int, eta_ext)
    r = ei / et
    s2 = r * r * (1 - wi[2] ** 2)
    if s2 >= 1:
        return None
    return np.array([-r * wi[0], -r * wi[1], -np.sign(wi[2]) * np.sqrt(1 - s2)])


# ------------------------------------------------------------------------------- host references (f64)
def fresnel(cos_i, eta_ext, eta_int):
    """Unpolarised dielectric Fresnel reflectance; cos_i < 0 arrives from inside (eta_int's side)."""
    with np.errstate(all="ignore"):
        cos_i = np.asarray(cos_i, np.float64)
        inside = cos_i < 0
        ei = np.where(inside, eta_int, eta_ext)
        et = np.where(inside, eta_ext, eta_int)
        c = np.abs(cos_i)
        sin2_t = (ei / et) ** 2 * np.maximum(0, 1 - c * c)
        tir = sin2_t >= 1
        ct = np.sqrt(np.maximum(0, 1 - sin2_t))
        rs = (ei * c - et * ct) / (ei * c + et * ct)
        rp = (et * c - ei * ct) / (et * c + ei * ct)
        return np.where(tir, 1.0, 0.5 * (rs * rs + rp * rp))


# ------------------------------------------------------------------------------------ chi-square runs
def lobe_grid(wi, alpha, targets=None, width: float = 12.0, floor: float = 0.02, squeeze: bool = False,
              n_fine: int = 400):
    """Integration points for the chi-square's cells, refined around specular peaks: `targets` (default: the
    mirror direction of wi). A lobe of roughness alpha spreads by about `width` alpha in the plane of incidence
    but only by `width` alpha |cos theta_i| across it (narrow at grazing angles, `floor` at least): refine at both
    scales; `squeeze`: also at 1.2 alpha, refraction out of air squeezing the lobe by about (1 - ext/int).
    No refinement for alpha None (no peak) or rough lobes (alpha >= 0.6)."""
    peaks = []
    if alpha is not None and alpha < 0.6:
        for d in (targets if targets is not None else [wi * np.array([-1, -1, 1])]):
            peaks.append((d, min(width * alpha, np.pi)))
            peaks.append((d, width * alpha * max(abs(wi[2]), floor)))
            if squeeze:
                peaks.append((d, 4 * alpha * 0.3))
    return refined_direction_grid(RES, SUB, peaks, n_fine=n_fine)


def bsdf_chi2(ctx, queue, row, wi, grid, n: int = N_SAMPLES, seed: int = 7, pdf_row=None, pdf_fn=None):
    """Sample `row` n times at wi, bin the smooth samples that carry weight (zero-weight samples dropped, as in Nori;
    a delta lobe's samples, MEASURE_DISCRETE, are not in the pdf, which holds the smooth lobes' selection probability),
    integrate pdf() of `pdf_row` (default the same row), or the host density `pdf_fn(dirs)`, over the cells with
    `grid` (from `lobe_grid` or `refined_direction_grid`). Returns (samples, keep, observed, expected)."""
    s = bsdf_sample_batch(ctx, queue, row, wi, n, seed)
    keep = (s.measure == 0) & np.any(s.weight != 0, axis=1)
    obs = bin_directions(s.wo[keep], RES)
    dirs, w, cell = grid
    if pdf_fn is not None:
        pdf = pdf_fn(dirs)
    else:
        pdf, _ = bsdf_pdf_eval_batch(ctx, queue, row if pdf_row is None else pdf_row, wi, dirs)
    exp = expected_from_grid(pdf, w, cell, (RES, 2 * RES), n)
    return s, keep, obs, exp


@dataclass
class BsdfRun:
    """One chi-square case's outcome: the samples, which carry weight, the test, the pdf's integral
    (expected counts summed) and wi."""
    samples: object
    keep: np.ndarray
    result: object
    total: float
    wi: np.ndarray


class BsdfRuns(dict):
    """Each case's run, computed when a test first asks for it. `case`: name -> (row, wi, grid) (rows and grids
    made lazily); every test is corrected over `n_tests` cases. (tests/bsdfs/conftest.py's `chi2_runs` fixture
    makes one per test file from its `chi2_case` and `CASES`.)"""

    def __init__(self, ctx, queue, case, n_tests: int, seed: int = 7, n: int = N_SAMPLES):
        super().__init__()
        self.ctx, self.queue, self.case, self.n_tests, self.seed, self.n = ctx, queue, case, n_tests, seed, n

    def __missing__(self, name):
        row, wi, grid = self.case(name)
        s, keep, obs, exp = bsdf_chi2(self.ctx, self.queue, row, wi, grid, self.n, self.seed)
        self[name] = BsdfRun(s, keep, chi2_test(obs, exp, min_exp=5.0, alpha=ALPHA, n_tests=self.n_tests),
                             exp.sum(), wi)
        return self[name]

    def check(self, name) -> None:
        """The case's samples pass the chi-square test against its pdf."""
        res = self[name].result
        assert res.passed, f"{name}: {res.message}"


def check_mixed_weights(s, keep, wi) -> None:
    """A BSDF with smooth and delta lobes: its smooth samples (`keep`) have weight f |cos| / pdf; its delta samples
    go to the mirror direction (a coating) or straight through (a mask's pass-through); every eta is 1."""
    assert np.all(np.isfinite(s.weight)) and np.all(s.weight >= 0)
    w, f, pdf, cos = s.weight[keep], s.f[keep], s.pdf[keep], np.abs(s.wo[keep, 2])
    assert np.all(pdf > 0), "a smooth sample with weight has zero pdf"
    np.testing.assert_allclose(w, f * (cos / pdf)[:, None], rtol=3e-4, atol=1e-7)
    delta = s.measure == 1
    mirror = np.all(np.abs(s.wo - wi * np.array([-1, -1, 1])) < 1e-5, axis=1)
    through = np.all(np.abs(s.wo + wi) < 1e-5, axis=1)
    assert np.all(mirror[delta] | through[delta])
    assert np.all(s.eta == 1.0)


def check_weights(s, keep) -> None:
    """A reflecting BSDF's kept samples have weight f cos / pdf (with cos = wo.z > 0 and pdf > 0), and a
    dropped (zero-weight) sample points below the surface or has f = 0."""
    assert np.all(s.measure == 0)
    assert np.all(np.isfinite(s.weight))
    w, f, pdf, cos = s.weight[keep], s.f[keep], s.pdf[keep], s.wo[keep, 2]
    assert np.all(pdf > 0), "a sample with weight has zero pdf"
    assert np.all(cos > 0)
    np.testing.assert_allclose(w, f * (cos / pdf)[:, None], rtol=2e-4, atol=1e-7)
    drop = ~keep
    assert np.all((s.wo[drop, 2] <= 0) | np.all(s.f[drop] == 0, axis=1))


# ------------------------------------------------------------------------------------------- energy
def mean_agrees(w, ref, a, rel=1e-3):
    """Student's t-test of the mean of w against ref at level a, except that a relative difference below
    `rel` (float32 arithmetic, quadrature) always passes: near-constant weights make the t-test too sharp."""
    from scipy import stats

    w = np.asarray(w, np.float64)
    if abs(w.mean() - ref) <= rel * abs(ref):
        return True, 1.0
    p = stats.ttest_1samp(w, ref).pvalue
    return p > a, p


def mean_le(w, bound, a) -> bool:
    """The mean of w is not significantly above bound (one-sided t-test at level a)."""
    from scipy import stats

    w = np.asarray(w, np.float64)
    if w.mean() <= bound:
        return True
    return stats.ttest_1samp(w, bound, alternative="greater").pvalue > a


def specular_grid(bsdf, wi, alphas):
    """`lobe_grid` for one of Mitsuba's rough plugins (`alphas`: its roughness, or the anisotropic pair): around the
    mirror direction and, for a dielectric (it has `int_ior`), the refracted one."""
    targets = [wi * np.array([-1, -1, 1])]
    if hasattr(bsdf, "int_ior"):
        t = refracted(wi, bsdf.ext_ior, bsdf.int_ior)
        if t is not None:
            targets.append(t)
    return lobe_grid(wi, max(alphas), targets, width=14.0, floor=0.03, squeeze=True, n_fine=300)


def mitsuba_rough_cases(kind: str, cases):
    """`chi2_case` for one of Mitsuba's rough plugins, `cases` a list of (name, keywords, wi, alphas)."""
    def chi2_case(name):
        _, kw, wi, alphas = next(c for c in cases if c[0] == name)
        bsdf = mitsuba_bsdf(kind, **kw)
        return bsdf.pack(), wi, specular_grid(bsdf, wi, alphas)

    return chi2_case


# ---------------------------------------------------------------------------------------- textured parameters
CHECKER_VALUES = ((0.2, 0.4, 0.6), (0.7, 0.5, 0.3))
UV1, UV2 = (0.1, 0.1), (0.6, 0.1)   # cells (0,0) and (1,0) of the default 0.5 grid: value1, value2


def mitsuba_bsdf_with_checkers(kind: str, names, **kw):
    """A Mitsuba-format BSDF with Nori checkerboard textures (CHECKER_VALUES) nested under `names` (any texture
    plugin does); other parameters as keywords (`mitsuba_props`)."""
    from .. import plugins  # noqa: F401
    from ..scene.properties import PropertyList
    from ..scene.registry import create
    from ..scene.spec import PluginSpec

    kids = []
    for name in names:
        tp = PropertyList('<texture type="checkerboard_color">')
        tp.add("value1", "color", CHECKER_VALUES[0])
        tp.add("value2", "color", CHECKER_VALUES[1])
        kids.append(PluginSpec("texture", "checkerboard_color", name, tp, [], None, format="nori"))
    pl = PropertyList(f'<bsdf type="{kind}">', fmt="mitsuba")
    for k, (t, v) in mitsuba_props(**kw).items():
        pl.add(k, t, v)
    return create(PluginSpec("bsdf", kind, None, pl, kids, None, format="mitsuba"))


def check_textured_like_constant(ctx, queue, kind: str, names, colour: str, transmit: bool = False) -> None:
    """`kind` with its alpha and `colour` textured (`names`) evaluates, where the checkerboard shows value1, as
    the constant plugin with alpha 0.2 and colour value1, elsewhere as alpha 0.7 and value2 (eval and pdf at 500
    directions above the surface, or below it if `transmit`)."""
    from ..device.dispatch import flag_defines

    rng = np.random.default_rng(4)
    wi = np.array([0.3, 0.2, 0.93])
    wo = rng.normal(size=(500, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    b = mitsuba_bsdf_with_checkers(kind, names)
    r = b.pack()
    assert r["flags"] & flag_defines()["BSDF_UV"]
    tex = b.textures_table
    for uv, a, c in ((UV1, 0.2, CHECKER_VALUES[0]), (UV2, 0.7, CHECKER_VALUES[1])):
        ref = mitsuba_row(kind, alpha=a, **{colour: c})
        wo_use = wo * np.array([1, 1, -1]) if transmit else wo
        p1, f1 = bsdf_pdf_eval_batch(ctx, queue, r, wi, wo_use, uv=uv, textures=tex)
        p2, f2 = bsdf_pdf_eval_batch(ctx, queue, ref, wi, wo_use, uv=uv)
        assert f2.max() > 0
        np.testing.assert_allclose(f1, f2, rtol=1e-5, atol=1e-7)
        np.testing.assert_allclose(p1, p2, rtol=1e-5, atol=1e-7)


# ------------------------------------------------------------------------------------------- renders
#: the polar angle (degrees, from the plane's normal) the furnace render's camera sees its plane at
FURNACE_THETA = 40.0


def furnace_plane_scene(bsdf_xml: str, fmt: str = "mitsuba", theta: float = FURNACE_THETA, radiance: float = 1.0,
                        size: int = 8, target=(0.0, 0.0)) -> str:
    """A scene (XML of format `fmt`, "nori" or "mitsuba") of one wide plane z = 0 (normal +z) made of the BSDF
    `bsdf_xml`, inside a constant environment of `radiance`, seen by a narrow camera (size x size pixels) at polar
    angle `theta` in the xz plane. Everything a ray leaving the plane meets is the environment, on either side, so
    the path integrator's image is the radiance times the BSDF's directional albedo ∫ f(wi, wo) |cos theta_o| dwo at
    wi = the direction to the camera (`furnace_wi`), reflection and transmission together. The camera looks at the
    point `target` (x, y) of the plane, where its uv is `furnace_uv(target)`. (The camera is narrow
    (0.05 degrees), so every pixel sees the same wi; many pixels of a few thousand samples rather than a few pixels
    of many keep the film's float32 sums exact enough, while the image mean has the error of all their samples.)"""
    t = np.radians(theta)
    x0, y0 = target
    o = ", ".join(f"{v:.9g}" for v in (x0 + 3 * np.sin(t), y0, 3 * np.cos(t)))
    tg = f"{x0:.9g}, {y0:.9g}, 0"
    if fmt == "nori":
        return (f'<scene><integrator type="path_mis"/><camera type="perspective"><float name="fov" value="0.05"/>'
                f'<integer name="width" value="{size}"/><integer name="height" value="{size}"/>'
                f'<transform name="toWorld"><lookat origin="{o}" target="{tg}" up="0, 0, 1"/></transform>'
                f'<rfilter type="box"/></camera>'
                f'<mesh type="obj"><string name="filename" value="plane.obj"/>{bsdf_xml}</mesh>'
                f'<emitter type="constant"><color name="radiance" value="{radiance!r}"/></emitter></scene>')
    return (f'<scene version="3.0.0"><integrator type="path"/><sensor type="perspective">'
            f'<float name="fov" value="0.05"/><transform name="to_world"><lookat origin="{o}" target="{tg}" '
            f'up="0, 0, 1"/></transform><film type="hdrfilm"><integer name="width" value="{size}"/>'
            f'<integer name="height" value="{size}"/><rfilter type="box"/></film></sensor>'
            f'<shape type="rectangle"><transform name="to_world"><scale value="50"/></transform>{bsdf_xml}</shape>'
            f'<emitter type="constant"><rgb name="radiance" value="{radiance!r}"/></emitter></scene>')


def furnace_uv(target=(0.0, 0.0)) -> np.ndarray:
    """The uv of the furnace plane (100 x 100, uv 0..1 over it, u along x, v along y) at the point `target`."""
    return 0.5 + np.asarray(target, np.float64) / 100.0


def furnace_wi(theta: float = FURNACE_THETA) -> np.ndarray:
    """The direction to the furnace render's camera in the plane's shading frame."""
    return wi_at(theta)


def render_furnace_plane(folder, bsdf_xml: str, fmt: str = "mitsuba", spp: int = 4096, seed: int = 1, **kw):
    """Render `furnace_plane_scene` (written to `folder`, with its plane mesh for Nori) and return the Film."""
    from pathlib import Path

    from .. import load_scene, render

    folder = Path(folder)
    (folder / "plane.obj").write_text("v -50 -50 0\nv 50 -50 0\nv 50 50 0\nv -50 50 0\n"
                                      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n")
    (folder / "furnace.xml").write_text(furnace_plane_scene(bsdf_xml, fmt, **kw))
    return render(load_scene(folder / "furnace.xml"), spp=spp, seed=seed)


def albedo_quadrature(ctx, queue, row, wi, grid) -> np.ndarray:
    """∫ f(wi, wo) |cos theta_o| dwo over the sphere by quadrature of the plugin's eval on `grid` (`lobe_grid`,
    `specular_grid`): independent of its sampling routine. RGB."""
    dirs, w, _ = grid
    _, f = bsdf_pdf_eval_batch(ctx, queue, row, wi, dirs)
    return (f.astype(np.float64) * (np.abs(dirs[:, 2]) * w)[:, None]).sum(0)


def check_render_value(film, reference, rel_tol: float = 0.0, alpha: float = ALPHA) -> None:
    """The image's mean (per channel) equals `reference` up to its standard error, a relative tolerance `rel_tol`
    of the reference itself (a quadrature's error) and the film's float32 sums (1e-4 relative: a pixel's sum of a
    few thousand equal values drifts by about 2e-5), by a z-test at level alpha."""
    from .stats import _ztest, mean_and_error

    m, se = mean_and_error(film)
    ref = np.broadcast_to(np.asarray(reference, np.float64), m.shape)
    res = _ztest(m - ref, se * se + ((rel_tol + 1e-4) * ref) ** 2, alpha, "furnace image mean vs reference")
    assert res.passed, f"{res.message}: image {m}, reference {ref}"


# ------------------------------------------------------------------------------------- reconstruction filters
FILTER_SRC = r"""
#include "rng.h"
#include "filter.h"
__kernel void offsets(__global const Camera* cam, __global const float* cdf, __global float4* out, uint n, uint seed) {
    uint i = get_global_id(0);
    if (i >= n) return;
    Sampler s;
    sampler_init(&s, seed, i, 0u);
    float w;
    float2 off = filter_sample(cam, cdf, next2d(&s), &w);
    out[i] = (float4)(off.x, off.y, w, 0.0f);
}
"""
N_FILTER = 400_000


def filter_camera(ftype: str, props_xml: str = "", fmt: str = "nori"):
    """An 8 x 8 camera with the reconstruction filter `<rfilter type=ftype>props_xml</rfilter>` (a Nori or Mitsuba
    file's)."""
    from .. import plugins  # noqa: F401
    from ..scene.registry import create
    from ..scene.xmlparser import parse_string

    if fmt == "nori":
        xml = (f'<scene><integrator type="normals"/><camera type="perspective"><integer name="width" value="8"/>'
               f'<integer name="height" value="8"/><rfilter type="{ftype}">{props_xml}</rfilter></camera></scene>')
    else:
        xml = (f'<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm"><integer name="width" '
               f'value="8"/><integer name="height" value="8"/><rfilter type="{ftype}">{props_xml}</rfilter></film>'
               f'</sensor></scene>')
    return create(parse_string(xml, "f.xml")).camera


def filter_offsets(ctx, queue, cam, n: int = N_FILTER, seed: int = 7):
    """n offsets (x, y) and weights w of the camera's filter_sample on the device, (n, 4); and its CDF table."""
    import pyopencl as cl

    from ..device.program import build_program

    kernel = cl.Kernel(build_program(ctx, FILTER_SRC), "offsets")
    row, table = cam.pack()
    mf = cl.mem_flags
    b_cam = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=row)
    b_cdf = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=table)
    out = np.zeros((n, 4), np.float32)
    b_out = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
    kernel(queue, (((n + 63) // 64) * 64,), (64,), b_cam, b_cdf, b_out, np.uint32(n), np.uint32(seed))
    cl.enqueue_copy(queue, out, b_out)
    queue.finish()
    return out, table


def cell_masses(table, radius, edges):
    """Probability of each [edges[k], edges[k+1]) under the piecewise-constant table pdf."""
    cdf = table.astype(np.float64)
    xs = np.linspace(-radius, radius, len(cdf))
    return np.diff(np.interp(edges, xs, cdf))


def check_filter_offsets(ctx, queue, cam, n_tests: int) -> None:
    """The filter's offsets stay within its radius and follow its own tabulated pdf (chi-square over 20 x 20
    cells, Šidák over `n_tests`)."""
    out, table = filter_offsets(ctx, queue, cam)
    r = cam.filter.radius
    assert np.all(np.abs(out[:, :2]) <= r + 1e-6)
    edges = np.linspace(-r, r, 21)
    obs, _, _ = np.histogram2d(out[:, 0], out[:, 1], bins=[edges, edges])
    m = cell_masses(table, r, edges)
    res = chi2_test(obs, np.outer(m, m) * len(out), alpha=ALPHA, n_tests=n_tests)
    assert res.passed, res.message


def check_filter_weights(ctx, queue, cam, n_tests: int) -> None:
    """E[w 1{x in cell}] / E[w] equals integral_cell f / integral f (separable, so per axis), for 8 cells over the
    filter's support: the weighted samples reproduce the filter, so an image converges to integral f L / integral f
    (Šidák over `n_tests` filters' cells)."""
    from scipy import stats
    from scipy.integrate import trapezoid

    out, _ = filter_offsets(ctx, queue, cam, seed=11)
    f = cam.filter
    r = f.radius
    edges = np.linspace(-r, r, 9)
    x = np.linspace(-r, r, 200001)
    fx = f.eval(x)
    total = trapezoid(fx, x)
    w = out[:, 2].astype(np.float64)
    zs = []
    for a, b in zip(edges[:-1], edges[1:]):
        sel = (out[:, 0] >= a) & (out[:, 0] < b)
        expect = trapezoid(np.where((x >= a) & (x <= b), fx, 0), x) / total
        v = w * sel
        ratio = v.sum() / w.sum()
        # delta-method standard error of a ratio of means
        se = np.sqrt(np.var(v - ratio * w) / len(w)) / w.mean()
        zs.append((ratio - expect) / max(se, 1e-12))
    p = 2 * stats.norm.sf(np.max(np.abs(zs)))
    assert p > 1 - (1 - ALPHA) ** (1 / (n_tests * len(zs))), (type(f).__name__, np.round(zs, 2))


EDGE_WIDTH = 16


def filter_edge_scene(ftype: str, props_xml: str = "", fmt: str = "nori") -> str:
    """A scene (XML of format `fmt`) whose image is a vertical step through its middle: a black half-plane x < 0 at
    z = 0 seen straight on (so its edge falls on raster x = EDGE_WIDTH / 2 whatever the perspective), a constant
    environment of radiance 1 beside it, EDGE_WIDTH x 2 pixels, reconstruction filter `ftype`. (Needs half.obj
    beside it for Nori: `render_filter_edge` writes it.)"""
    cam = '<lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>'
    if fmt == "nori":
        return (f'<scene><integrator type="path_mis"/><camera type="perspective"><float name="fov" value="30"/>'
                f'<integer name="width" value="{EDGE_WIDTH}"/><integer name="height" value="2"/>'
                f'<transform name="toWorld">{cam}</transform><rfilter type="{ftype}">{props_xml}</rfilter></camera>'
                f'<mesh type="obj"><string name="filename" value="half.obj"/><bsdf type="diffuse"><color '
                f'name="albedo" value="0"/></bsdf></mesh>'
                f'<emitter type="constant"><color name="radiance" value="1"/></emitter></scene>')
    return (f'<scene version="3.0.0"><integrator type="path"/><sensor type="perspective"><float name="fov" '
            f'value="30"/><transform name="to_world">{cam}</transform><film type="hdrfilm"><integer name="width" '
            f'value="{EDGE_WIDTH}"/><integer name="height" value="2"/><rfilter type="{ftype}">{props_xml}</rfilter>'
            f'</film></sensor><shape type="rectangle"><transform name="to_world"><scale x="50" y="100"/>'
            f'<translate x="-50"/></transform><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>'
            f'</shape><emitter type="constant"><rgb name="radiance" value="1"/></emitter></scene>')


def check_filter_edge_render(folder, ftype: str, props_xml: str = "", fmt: str = "nori", spp: int = 4096) -> None:
    """Render `filter_edge_scene`: each pixel j is the filter's share beyond the edge, integral from
    EDGE_WIDTH / 2 - (j + 0.5) to r of f over integral f (or one minus it, as the camera's x runs), by a z-test per
    pixel against that host integral of the plugin's own eval (Šidák over the image)."""
    from pathlib import Path

    from scipy.integrate import trapezoid

    from .. import load_scene, render
    from .stats import compare_to_value

    folder = Path(folder)
    (folder / "half.obj").write_text("v -100 -100 0\nv 0 -100 0\nv 0 100 0\nv -100 100 0\nf 1 2 3 4\n")
    (folder / "edge.xml").write_text(filter_edge_scene(ftype, props_xml, fmt))
    scene = load_scene(folder / "edge.xml")
    f = scene.camera.filter
    r = f.radius
    x = np.linspace(-r, r, 400001)
    fx = f.eval(x)
    total = trapezoid(fx, x)
    beyond = np.array([trapezoid(np.where(x > EDGE_WIDTH / 2 - (j + 0.5), fx, 0), x) / total
                       for j in range(EDGE_WIDTH)])
    assert 0 < beyond[EDGE_WIDTH // 2] < 1 and beyond[0] == 0 and abs(beyond[-1] - 1) < 1e-9
    film = render(scene, spp=spp, seed=3)
    if film.image[:, 0].mean() > 0.5:   # the camera's x runs the other way: the environment on the left
        beyond = 1 - beyond
    ref = np.broadcast_to(beyond[None, :, None], film.image.shape)
    res = compare_to_value(film, ref, ALPHA)
    assert res.passed, f"{res.message}: row {film.image[0, :, 0].round(4)}, expected {beyond.round(4)}"


# ------------------------------------------------------------------------------------------------ textures
TEXTURE_SRC = r"""
#include "texture.h"
__kernel void tex_eval(__global const Texture* textures, uint idx, uint n, __global const float2* uv,
                       __global float4* out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    out[i] = vf4(texture_eval(textures + idx, uv[i]), 0.0f);
}
"""
#: where the textured furnace plane is seen: uv (0.63, 0.62), inside a cell of every checkerboard tested
TEXTURE_TARGET = (13.0, 12.0)


def texture_eval_batch(ctx, queue, textures, uv):
    """Evaluate every texture in `textures` (placed in one table, after a decoy) at uv (N, 2) on the device."""
    import pyopencl as cl

    from ..device.program import build_program
    from ..scene import registry
    from ..textures.texture import TextureTable

    kernel = cl.Kernel(build_program(ctx, TEXTURE_SRC), "tex_eval")
    table = TextureTable()
    table.add(registry.instantiate("texture", "checkerboard", {}, fmt="mitsuba"))   # not at row 0
    rows = [table.add(t) for t in textures]
    arr = table.array()
    ro = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
    tbuf = cl.Buffer(ctx, ro, hostbuf=arr)
    uv = np.ascontiguousarray(uv, np.float32)
    ubuf = cl.Buffer(ctx, ro, hostbuf=uv)
    n = len(uv)
    obuf = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, size=n * 16)
    outs = []
    for r in rows:
        kernel(queue, ((n + 63) // 64 * 64,), (64,), tbuf, np.uint32(r), np.uint32(n), ubuf, obuf)
        out = np.empty((n, 4), np.float32)
        cl.enqueue_copy(queue, out, obuf)
        outs.append(out[:, :3])
    return outs


def check_texture_render(folder, texture_xml: str, fmt: str = "nori", spp: int = 256) -> None:
    """A diffuse furnace plane whose albedo is the texture `texture_xml` (named `albedo` for Nori, `reflectance`
    for Mitsuba), seen at TEXTURE_TARGET: the image is the texture's value there, its host eval at that uv (exactly:
    a diffuse plane in a constant environment of radiance 1 reflects its albedo, whatever direction it samples)."""
    from .. import load_scene

    film = render_furnace_plane(folder, f'<bsdf type="diffuse">{texture_xml}</bsdf>', fmt, spp=spp,
                                target=TEXTURE_TARGET)
    texture = load_scene(folder / "furnace.xml").shapes[0].bsdf.texture   # the plane's diffuse albedo
    check_render_value(film, texture.eval(furnace_uv(TEXTURE_TARGET)[None, :])[0])
