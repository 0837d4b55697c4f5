"""Our own Nori test files (tests/nori/*.xml) through the same runner as `clrender test`, and the runner's
verdicts: it must fail on a broken BSDF, on wrong references, and exit non-zero."""
from pathlib import Path

import pytest

from clrender.cli import main

NORI = Path(__file__).resolve().parent / "nori"
FILES = sorted(NORI.glob("*.xml"))


# scene_ttest.xml renders four whole scenes to the t-test's precision (80 s here): in the slow suite (.ci/run).
SLOW = {"scene_ttest.xml"}


@pytest.mark.parametrize("path", [pytest.param(p, marks=pytest.mark.slow) if p.name in SLOW else p for p in FILES],
                         ids=[p.name for p in FILES])
def test_our_test_files_pass(path, capsys):
    code = main(["test", str(path), "--seed", "1"])
    out = capsys.readouterr().out
    assert code == 0, out
    assert " 0 failed" in out


def test_wrong_reference_fails(tmp_path, capsys):
    text = (NORI / "bsdf_ttest.xml").read_text().replace("0.464596, 0.465451", "0.47, 0.465451")
    p = tmp_path / "wrong.xml"
    p.write_text(text)
    assert main(["test", str(p)]) == 1
    out = capsys.readouterr().out
    assert "FAIL" in out and "1 failed" in out


def test_checkerboard_references_are_its_scenes_integrated():
    """checkerboard_ttest.xml's references are its own scenes integrated in numpy (tests/nori/checkerboard_refs.py,
    which reads the file), and where a case has a delta, delta in uv units instead of cells moves it far (> 10 %)
    from its reference: an edit of the scenes that leaves a reference stale, or a case that no longer tells the
    conventions apart, fails here."""
    import importlib.util

    import numpy as np

    spec = importlib.util.spec_from_file_location("checkerboard_refs", NORI / "checkerboard_refs.py")
    refs_mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(refs_mod)
    refs, cases = refs_mod.read_cases()
    assert len(refs) == len(cases) == 4
    for ref, case in zip(refs, cases):
        mean, se = refs_mod.pixel_mean(case, 400_000, seed=7)
        assert abs(mean - ref) < 5 * se, (case, mean, se, ref)
        if np.any(case["delta"]):
            wrong = refs_mod.pixel_mean(dict(case, variant="uv_delta"), 100_000, seed=8)[0]
            assert abs(wrong - ref) > 0.1 * ref, (case, wrong, ref)


def test_broken_bsdf_fails_chi2_with_histograms(tmp_path, capsys, monkeypatch):
    """A microfacet whose pdf() is wrong (alpha given to pdf differs from the sampled one) must fail, and
    the failing case's histograms must be written beside the file."""
    p = tmp_path / "chi2.xml"
    p.write_text('<test type="chi2test"><integer name="testCount" value="2"/><bsdf type="microfacet">'
                 '<float name="alpha" value="0.3"/><color name="kd" value="0"/></bsdf></test>')
    import clrender.testing.kernels as K

    real = K.bsdf_pdf_eval_batch

    def wrong_pdf(ctx, queue, rows, wi, wo, **kw):
        import numpy as np

        rows = np.array(rows, copy=True)
        rows["microfacet"]["alpha"] *= 1.3  # the pdf of a rougher surface than the one sampled
        return real(ctx, queue, rows, wi, wo, **kw)

    monkeypatch.setattr(K, "bsdf_pdf_eval_batch", wrong_pdf)
    assert main(["test", str(p)]) == 1
    out = capsys.readouterr().out
    assert "FAIL" in out and "histograms:" in out
    assert list(tmp_path.glob("chi2_chi2_*.png"))


@pytest.mark.parametrize("warp,param", [("square", None), ("tent", None), ("disk", None), ("triangle", None),
                                        ("sphere", None), ("hemisphere", None), ("cosine_hemisphere", None),
                                        ("cone", 20.0), ("beckmann", 0.2)])
def test_warptest(tmp_path, warp, param, capsys):
    args = ["warptest", warp] + ([str(param)] if param is not None else []) + [
        "--samples", "400000", "--plot", str(tmp_path / "w.png")]
    assert main(args) == 0, capsys.readouterr().out
    assert (tmp_path / "w.png").exists()


def test_t_statistic_floors_the_variance_as_nori():
    """t = |mean - ref| · sqrt(n / max(var, 1e-5)): a deterministic estimator passes when right, fails when off."""
    from clrender.testing.nori import t_test

    assert t_test(0.25, 0.0, 100000, 0.25, 0.01)[0]
    assert t_test(0.25 + 1e-6, 0.0, 100000, 0.25, 0.01)[0]       # t = 0.1
    assert not t_test(0.25 + 1e-4, 0.0, 100000, 0.25, 0.01)[0]   # t = 10
    assert not t_test(0.26, 0.04, 100000, 0.25, 0.01)[0]          # t = 15.8 from the real variance


def test_scene_samples_cover_the_image_without_a_filter(tmp_path, capsys):
    """Nori's scene ttest draws film positions over [0,W)x[0,H) only, never a filter footprint: a light that
    is just outside the image contributes exactly 0 (a filtered render of the pixel would see it), and a
    deterministic 0 passes thanks to the variance floor."""
    p = tmp_path / "outside.xml"
    p.write_text(f'''<test type="ttest"><string name="references" value="0"/><integer name="sampleCount" value="20000"/>
        <scene><integrator type="path_mis"/>
            <camera type="perspective"><integer name="width" value="1"/><integer name="height" value="1"/>
                <float name="fov" value="10"/><rfilter type="gaussian"/></camera>
            <mesh type="obj"><string name="filename" value="{NORI / 'light_down.obj'}"/>
                <transform name="toWorld"><translate value="0.6, 0, 1"/></transform>
                <emitter type="area"><color name="radiance" value="10"/></emitter></mesh>
        </scene></test>''')
    assert main(["test", str(p)]) == 0, capsys.readouterr().out
    out = capsys.readouterr().out
    assert "estimate 0 " in out
    # The same scene as a render: a splatting film (the default, as Nori's) has samples inside the image only and
    # sees nothing either; filter importance sampling's gaussian footprint reaches past the pixel and sees the light.
    import clrender
    from clrender.scene.registry import create
    from clrender.scene.xmlparser import parse_file

    scene = create(parse_file(str(p)).children[0])
    assert clrender.render(scene, spp=4096).image.max() == 0.0
    assert clrender.render(scene, spp=4096, reconstruction="sampling").image.mean() > 0.01


CHI2 = "<test type='chi2test'>\n  {prop}\n  <bsdf type='diffuse'/>\n</test>\n"
TTEST = ("<test type='ttest'>\n  {prop}\n  <string name='angles' value='0'/>\n"
         "  <string name='references' value='{refs}'/>\n  <bsdf type='diffuse'/>\n</test>\n")


@pytest.mark.parametrize("text,what", [
    # each used to end in a traceback (a complex p-value, a reshape, a division by zero) or to pass vacuously
    (CHI2.format(prop="<float name='significanceLevel' value='2'/>"), "significanceLevel"),
    (CHI2.format(prop="<integer name='resolution' value='-3'/>"), "resolution"),
    (CHI2.format(prop="<integer name='sampleCount' value='-5'/>"), "sampleCount"),
    (CHI2.format(prop="<integer name='testCount' value='0'/>"), "testCount"),
    (TTEST.format(prop="<integer name='sampleCount' value='0'/>", refs="0.5"), "sampleCount"),
    (TTEST.format(prop="", refs="nan"), ":4:3: 'references'"),
])
def test_bad_test_file_properties_are_located_errors(tmp_path, capsys, text, what):
    p = tmp_path / "t.xml"
    p.write_text(text)
    assert main(["test", str(p), "--no-plots"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and "t.xml:" in err and what in err, err
    assert "t.xml:2:" in err or what.startswith(":4:"), err


@pytest.mark.parametrize("args,what", [
    (["cone", "nan"], "half-angle"), (["cone", "-10"], "half-angle"), (["beckmann", "0"], "alpha"),
    (["square", "--samples", "-5"], "--samples"), (["square", "--samples", "0"], "--samples"),
    (["square", "3"], "no parameter"),
])
def test_warptest_refuses_bad_parameters(tmp_path, capsys, args, what):
    # these used to run and FAIL (a NaN cone), crash inside numpy (negative samples) or pass vacuously (0 samples)
    assert main(["warptest", *args, "--plot", str(tmp_path / "w.png")]) == 2
    err = capsys.readouterr().err
    assert what in err, err
    assert not (tmp_path / "w.png").exists()


def test_unwritable_json_fails_before_the_tests_run(tmp_path, capsys):
    p = tmp_path / "t.xml"
    p.write_text(CHI2.format(prop="<integer name='testCount' value='1'/>"))
    assert main(["test", str(p), "--json", "/proc/clrender-x.json"]) == 2
    out = capsys.readouterr()
    assert "/proc/clrender-x.json" in out.err and "PASS" not in out.out  # it used to test first, then fail
