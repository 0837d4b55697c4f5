"""Nori's statistical test files (`<test type="ttest">`, `<test type="chi2test">`), run on any OpenCL device.

ttest: Student's t-test of the mean luminance of sample weights against each reference, Šidák-corrected
over all references of the file.
- `bsdf` children: the weights f·cos/pdf of `sample()` at wi = (sin θ, 0, cos θ) for each of `angles`
  (references in BSDF-major order).
- emitter children (a `point`, `distantdisk`, ... emitter, or a `mesh` with an `area` emitter): the weights
  radiance/pdf of `sample()` seen from the reference point (0, 0, d) for each of `distances` (default: the
  origin only), in emitter-major order.
- `scene` children: one reference per scene; as in Nori, each sample is a film position drawn uniformly over
  the whole image [0,W)×[0,H) (no reconstruction filter, no pixel footprint) and the luminance of Li along
  its camera ray (kernels/image_samples.cl).
The t statistic is Nori's: t = |mean − ref| · sqrt(n / max(var, 1e-5)) with var the sample variance, so an
estimator that is deterministic (a point light seen through a pinhole) passes when it is right.
chi2test: for each `bsdf`, `testCount` incident directions (cosine-distributed, from --seed), samples binned
on the sphere (`resolution` cos θ bins × 2·resolution φ bins) against the integral of `pdf()` over each
cell, small cells pooled, Šidák-corrected over testCount × BSDFs. A failing case writes its observed and
expected histograms as a PNG beside the test file.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..device.kernelargs import KernelArgs
from ..errors import SceneError, SourceLocation
from ..scene.registry import register
from .chi2 import bin_directions, chi2_test, expected_from_grid, refined_direction_grid, sidak
from .kernels import LOCAL, padded

LUM = np.array([0.212671, 0.715160, 0.072169])


def _numbers(props, name, default=None):
    if not props.has(name):
        if default is None:
            raise SceneError(f"missing required property '{name}' of <test>", props.owner_location)
        return list(default)
    text = props.get_string(name)
    try:
        values = [float(t) for t in text.replace(",", " ").split()]
    except ValueError:
        raise SceneError(f"'{name}' must be a list of numbers, got '{text}'", props.location(name)) from None
    if not all(math.isfinite(v) for v in values):
        raise SceneError(f"'{name}' must be a list of finite numbers, got '{text}'", props.location(name))
    return values


def _checked(props, name, value, low, high=None, what=""):
    """`value` of property `name`, or an error at its line unless low <= value (<= high)."""
    if not (value >= low and (high is None or value <= high)):
        want = what or (f"between {low} and {high}" if high is not None else f"at least {low}")
        raise SceneError(f"{name} must be {want}, got {value}", props.location(name))
    return value


#: sample counts index 32-bit work-items on the device
MAX_SAMPLES = 2**31 - 1


class _TestFile:
    children = ("bsdf", "emitter", "scene", "mesh")

    def __init__(self, props, children, spec):
        self.location = spec.location
        self.alpha = props.get_float("significanceLevel", 0.01)
        if not 0 < self.alpha < 1:
            raise SceneError(f"significanceLevel must be between 0 and 1 (exclusive), got {self.alpha}",
                             props.location("significanceLevel"))
        self.items = children


@register("test", "ttest")
class TTestFile(_TestFile):
    def __init__(self, props, children, spec):
        super().__init__(props, children, spec)
        self.sample_count = _checked(props, "sampleCount", props.get_int("sampleCount", 100000), 2, MAX_SAMPLES)
        self.angles = _numbers(props, "angles", [0.0]) if props.has("angles") else []
        self.distances = _numbers(props, "distances", [0.0]) if props.has("distances") else [0.0]
        self.references = _numbers(props, "references")
        n_bsdf = sum(1 for c in children if c.spec.tag == "bsdf")
        n_em = sum(1 for c in children if c.spec.tag in ("emitter", "mesh"))
        n_scene = sum(1 for c in children if c.spec.tag == "scene")
        if n_bsdf and not self.angles:
            raise SceneError("a ttest of BSDFs needs 'angles'", spec.location)
        expected = n_bsdf * len(self.angles) + n_em * len(self.distances) + n_scene
        if expected != len(self.references):
            raise SceneError(f"{len(self.references)} references given, but the test has {expected} cases "
                             f"({n_bsdf} BSDF(s) × {len(self.angles)} angle(s), {n_em} emitter(s) × "
                             f"{len(self.distances)} distance(s), {n_scene} scene(s))", props.location("references"))


@register("test", "chi2test")
class Chi2TestFile(_TestFile):
    def __init__(self, props, children, spec):
        super().__init__(props, children, spec)
        self.resolution = _checked(props, "resolution", props.get_int("resolution", 10), 1, 4096)
        self.min_exp = _checked(props, "minExpFrequency", props.get_float("minExpFrequency", 5.0), 0.0,
                                what="0 or more")
        self.sample_count = _checked(props, "sampleCount",
                                     props.get_int("sampleCount", self.resolution * 2 * self.resolution * 5000),
                                     1, MAX_SAMPLES)
        self.test_count = _checked(props, "testCount", props.get_int("testCount", 5), 1, 10**6)
        for c in children:
            if c.spec.tag != "bsdf":
                raise SceneError("a chi2test takes only <bsdf> children", c.spec.location)


@dataclass
class CaseResult:
    file: str
    kind: str
    what: str
    passed: bool
    p_value: float
    reference: float | None = None
    estimate: float | None = None
    std_error: float | None = None
    detail: str = ""
    extra: dict = field(default_factory=dict)

    def line(self) -> str:
        status = "PASS" if self.passed else "FAIL"
        if self.reference is not None:
            body = (f"reference {self.reference:.6g}, estimate {self.estimate:.6g} ± {self.std_error:.3g}, "
                    f"p = {self.p_value:.4g}")
        else:
            body = f"p = {self.p_value:.4g}; {self.detail}"
        return f"{status}  {self.kind:6s} {self.what}: {body}"


def _describe_plugin(obj) -> str:
    spec = obj.spec
    if spec is None:
        return "default"
    parts = []
    for name in spec.props.names():
        raw = spec.props.raw(name)
        parts.append(f"{name}={raw}")
    return f'{spec.tag} "{spec.type}"' + (f" ({', '.join(parts)})" if parts else "")


#: Nori's floor on the sample variance in its t statistic (hypothesis.cpp)
VARIANCE_FLOOR = 1e-5


def t_test(mean: float, variance: float, n: int, reference: float, alpha_corrected: float):
    """Nori's two-sided Student's t-test of a sample mean against a reference: (passed, p-value)."""
    from scipy import stats

    t = abs(mean - reference) * math.sqrt(n / max(variance, VARIANCE_FLOOR))
    p = float(2 * stats.t.sf(t, max(n - 1, 1)))
    return p >= alpha_corrected, p


class _EmitterScene:
    """A scene holding just one emitter (and its mesh), to pack the tables its sampling needs."""

    def __init__(self, item):
        from ..cameras.perspective import PerspectiveCamera  # noqa: F401 (registers)
        from ..integrators.integrator import Integrator

        if item.spec.tag == "mesh":
            if item.emitter is None:
                raise SceneError("a <mesh> in a ttest must carry an emitter", item.spec.location)
            self.shapes, self.emitters = [item], []
        else:
            self.shapes, self.emitters = [], [item]
        self.integrator = Integrator()
        self.camera = _DummyCamera()


class _DummyCamera:
    width = height = 1

    def pack(self):
        from ..device import layout

        row = layout.zeros("Camera")
        row["filter_bins"] = 1
        return row, np.array([0.0, 1.0], np.float32)


EMITTER_SRC = '#include "testing/emitter_batch.cl"\n'  # kernels/testing/emitter_batch.cl


class Runner:
    """Runs test files on one device and collects CaseResults."""

    def __init__(self, device=None, seed: int = 0, plots: bool = True, nori_dialect: str | None = None):
        from ..device.context import get_context
        from ..scene.dialect import resolve

        self.dialect = resolve(nori_dialect)
        self.ctx, self.queue = get_context(device)
        self.seed = seed
        self.plots = plots

    # -- files ----------------------------------------------------------------------------------------
    def run_file(self, path) -> list[CaseResult]:
        from .. import plugins  # noqa: F401
        from ..scene.registry import create
        from ..scene.xmlparser import parse_file

        path = Path(path)
        spec = parse_file(str(path), nori_dialect=self.dialect)
        if spec.tag != "test":
            raise SceneError(f"expected a <test> file, found <{spec.tag}> (use `clrender render` for scenes)",
                             SourceLocation(str(path), spec.location.line, spec.location.col))
        test = create(spec)
        if isinstance(test, TTestFile):
            return self._ttest(path, test)
        return self._chi2(path, test)

    # -- ttest ----------------------------------------------------------------------------------------
    def _ttest(self, path, test: TTestFile) -> list[CaseResult]:
        from .kernels import bsdf_sample_batch

        n_cases = len(test.references)
        a = sidak(test.alpha, n_cases)
        refs = iter(test.references)
        out = []
        n = test.sample_count
        for item in test.items:
            tag = item.spec.tag
            if tag == "bsdf":
                row = item.pack()
                for ang in test.angles:
                    th = math.radians(ang)
                    wi = np.array([math.sin(th), 0.0, math.cos(th)])
                    s = bsdf_sample_batch(self.ctx, self.queue, row, wi, n, seed=self.seed,
                                          textures=item.textures_table, tables=item.bsdf_tables)
                    lum = s.weight.astype(np.float64) @ LUM
                    out.append(self._tcase(path, "bsdf", f"{_describe_plugin(item)}, angle {ang:g}°", lum,
                                           next(refs), a))
            elif tag in ("emitter", "mesh"):
                for dist in test.distances:
                    lum = self._emitter_samples(item, dist, n) @ LUM
                    out.append(self._tcase(path, "emitter", f"{_describe_plugin(item if tag == 'emitter' else item.emitter)}"
                                           f", reference point (0, 0, {dist:g})", lum, next(refs), a))
            else:
                out.append(self._scene_case(path, item, n, next(refs), a))
        return out

    def _tcase(self, path, kind, what, lum, ref, a):
        lum = np.where(np.isfinite(lum), lum, np.nan)
        bad = int(np.isnan(lum).sum())
        lum = np.nan_to_num(lum)
        m = float(lum.mean())
        var = float(lum.var(ddof=1)) if len(lum) > 1 else 0.0
        se = math.sqrt(var / len(lum))
        ok, p = t_test(m, var, len(lum), ref, a)
        if bad:
            ok = False
        return CaseResult(str(path), kind, what, ok, p, ref, m, se,
                          detail=f"{bad} NaN/Inf sample weights" if bad else "")

    def _emitter_samples(self, item, dist, n):
        from ..renderer import render_defines
        import pyopencl as cl

        from ..device.program import build_program
        from ..pack import pack_scene

        buffers = pack_scene(_EmitterScene(item))
        prg = build_program(self.ctx, EMITTER_SRC, defines=render_defines(None, buffers))
        k = cl.Kernel(prg, "emitter_sample_batch")
        mf = cl.mem_flags
        # (pyopencl's set_arg keeps no reference: the buffers must stay alive while the kernel runs)
        bufs = {t: cl.Buffer(self.ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(x))
                for t, x in buffers.tables.items()}
        args = KernelArgs(k).set_scene(bufs)
        args.set(e=np.uint32(0), ref=np.array([0, 0, dist, 0], np.float32), seed=np.uint32(self.seed))
        out = np.empty((n, 4), np.float32)
        chunk = 1 << 20
        for s in range(0, n, chunk):
            m = min(chunk, n - s)
            d_out = cl.Buffer(self.ctx, mf.WRITE_ONLY, m * 16)
            args.set(n=np.uint32(m), first=np.uint32(s), out=d_out)
            cl.enqueue_nd_range_kernel(self.queue, k, (padded(m),), (LOCAL,))   # one compiled variant
            cl.enqueue_copy(self.queue, out[s:s + m], d_out)
        self.queue.finish()
        return out[:, :3].astype(np.float64)

    def _scene_case(self, path, scene, n, ref, a):
        lum = self._image_samples(scene, n) @ LUM
        what = f"scene with {scene.integrator.kernel} ({scene.width}×{scene.height}, {n} image samples)"
        return self._tcase(path, "scene", what, lum, ref, a)

    def _image_samples(self, scene, n):
        """Li (RGB, float64) of `n` camera rays through uniform positions over the whole image."""
        from ..renderer import render_defines

        import pyopencl as cl

        from ..device.program import build_program
        from ..pack import pack_scene

        b = pack_scene(scene)
        prg = build_program(self.ctx, '#include "image_samples.cl"\n', defines=render_defines(scene, b))
        k = cl.Kernel(prg, "image_samples")
        mf = cl.mem_flags
        ro = mf.READ_ONLY | mf.COPY_HOST_PTR
        # (pyopencl's set_arg keeps no reference: the buffers must stay alive while the kernel runs)
        bufs = {t: cl.Buffer(self.ctx, ro, hostbuf=np.ascontiguousarray(x)) for t, x in b.tables.items()}
        cam = cl.Buffer(self.ctx, ro, hostbuf=b.camera)
        args = KernelArgs(k).set_scene(bufs)
        chunk = 1 << 16  # short launches; one fixed shape so PoCL compiles it once
        d_out = cl.Buffer(self.ctx, mf.WRITE_ONLY, chunk * 16)
        args.set(cam=cam, out=d_out, seed=np.uint32(self.seed))
        out = np.empty((n, 4), np.float32)
        for s in range(0, n, chunk):
            m = min(chunk, n - s)
            args.set(first=np.uint32(s), n=np.uint32(m))
            cl.enqueue_nd_range_kernel(self.queue, k, (chunk,), (64,))
            cl.enqueue_copy(self.queue, out[s:s + m], d_out)
        self.queue.finish()
        return out[:, :3].astype(np.float64)

    # -- chi2test -------------------------------------------------------------------------------------
    def _chi2(self, path, test: Chi2TestFile) -> list[CaseResult]:
        from .kernels import bsdf_pdf_eval_batch, bsdf_sample_batch

        res = test.resolution
        n_tests = test.test_count * len(test.items)
        rng = np.random.default_rng(self.seed)
        out = []
        for bi, item in enumerate(test.items):
            row = item.pack()
            alpha = float(getattr(item, "alpha", 0.0) or 0.0)
            for t in range(test.test_count):
                u = rng.random(2)
                r, phi = math.sqrt(u[0]), 2 * math.pi * u[1]
                wi = np.array([r * math.cos(phi), r * math.sin(phi), math.sqrt(max(0.0, 1 - u[0]))])
                s = bsdf_sample_batch(self.ctx, self.queue, row, wi, test.sample_count, seed=self.seed + 7919 * t,
                                      textures=item.textures_table, tables=item.bsdf_tables)
                ok_w = np.any(s.weight != 0, axis=1) & np.all(np.isfinite(s.weight), axis=1)
                observed = bin_directions(s.wo[ok_w], res)
                peaks = []
                if alpha > 0:
                    refl = np.array([-wi[0], -wi[1], wi[2]])
                    peaks = [(refl, min(math.pi, 12 * alpha)), (refl, min(math.pi, 3 * alpha))]
                dirs, weights, cell = refined_direction_grid(res, sub=8, peaks=peaks, n_fine=200 if peaks else 0)
                pdf, _ = bsdf_pdf_eval_batch(self.ctx, self.queue, row, np.broadcast_to(wi, dirs.shape), dirs,
                                             textures=item.textures_table, tables=item.bsdf_tables)
                expected = expected_from_grid(pdf, weights, cell, (res, 2 * res), test.sample_count)
                r_ = chi2_test(observed, expected, test.min_exp, test.alpha, n_tests)
                what = f"{_describe_plugin(item)}, wi = ({wi[0]:.3f}, {wi[1]:.3f}, {wi[2]:.3f})"
                case = CaseResult(str(path), "chi2", what, r_.passed, r_.p_value, detail=r_.message)
                if not r_.passed and self.plots:
                    png = Path(path).with_name(f"{Path(path).stem}_chi2_{bi}_{t}.png")
                    write_histograms(png, observed, expected, what)
                    case.extra["plot"] = str(png)
                    case.detail += f"; histograms: {png}"
                out.append(case)
        return out


def write_histograms(path, observed, expected, title=""):
    """Observed and expected counts side by side (rows: cos θ from -1 at the bottom, columns: φ)."""
    from PIL import Image, ImageDraw

    from ..film import _atomic_write

    vmax = max(float(observed.max()), float(expected.max()), 1.0)
    scale = 24

    def panel(h):
        g = np.clip(h[::-1] / vmax, 0, 1)
        rgb = np.stack([g ** 0.5, g ** 1.5, 1 - g], axis=-1)
        rgb = (np.repeat(np.repeat(rgb, scale, axis=0), scale, axis=1) * 255).astype(np.uint8)
        return Image.fromarray(rgb, "RGB")

    a, b = panel(observed), panel(expected)
    img = Image.new("RGB", (a.width * 2 + 30, a.height + 40), "white")
    img.paste(a, (10, 30))
    img.paste(b, (a.width + 20, 30))
    d = ImageDraw.Draw(img)
    d.text((10, 5), "observed", fill="black")
    d.text((a.width + 20, 5), "expected", fill="black")
    d.text((10, 18), title[:120], fill="black")
    return _atomic_write(Path(path), lambda tmp: img.save(str(tmp), format="PNG"))


def run_files(paths, device=None, seed: int = 0, plots: bool = True) -> list[CaseResult]:
    runner = Runner(device=device, seed=seed, plots=plots)
    results = []
    for p in paths:
        results.extend(runner.run_file(p))
    return results


def results_json(results) -> list[dict]:
    return [asdict(r) for r in results]
