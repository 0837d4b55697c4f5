"""Adaptive sampling (clrender/adaptive.py): rounds over lists of pixels in both executors.

- A pixel's n samples are exactly those a uniform render of n spp gives it (the list launches number samples as the
  range launches do): per pixel, the adaptive value equals the uniform render's at that pixel's count.
- The same seed and options give the same image and counts however a round is cut into launches or waves.
- Unbiased enough to trust: in a closed furnace (every wall diffuse 0.5 and emitting 1: radiance 2 everywhere,
  exactly) every pixel and the image mean agree with 2 within their errors, and per pixel the adaptive image agrees
  with a uniform render of the same total samples.
- The stopping rule: a pixel stops when it meets the target, never before min_spp; a time limit keeps true counts.
- The command line: the count layer in the EXR; refused combinations exit with status 2 and say why.
- Even noise: after the first round a render whose potential gain is small (the closed furnace) finishes as the
  uniform render of one spp, the very image of a uniform render; an uneven one (the Cornell box) stays adaptive;
  with the switch off, the stopping rule keeps the furnace's mean exact.
"""
from pathlib import Path

import numpy as np
import pytest

import clrender
from clrender.adaptive import UNIFORM_BELOW, AdaptiveOptions, pooled_error, predicted_allocation, variance_bound
from clrender.renderer import Renderer
from clrender.testing.stats import compare_films, compare_mean_to_value

from analytic_scenes import furnace_scene
from test_oclgrind import _run_under_oclgrind, needs_oclgrind


def sampling_renderer(scene, **kw):
    """The filter-sampling film, which the wavefront and the feature AOVs take, and adaptive sampling where a
    splatting film's store would not fit (tests/test_adaptive_splat.py tests adaptive sampling on the splatting
    film): the uniform renders it is compared with here are of the same film."""
    return Renderer(scene, reconstruction="sampling", **kw)


SCENES = Path(__file__).resolve().parents[1] / "scenes"
OPTS = dict(target_error=0.1, max_spp=64, seed=5)


def small_cornell(size=32):
    s = clrender.load_scene(SCENES / "cornell" / "cornell_path_mis.xml")
    s.camera.width = s.camera.height = size
    return s


@pytest.fixture(scope="module")
def cornell():
    return small_cornell()


@pytest.fixture(scope="module")
def adaptive_film(cornell):
    return sampling_renderer(cornell, driver="megakernel").render_adaptive(**OPTS)


def test_options_and_rounds():
    o = AdaptiveOptions.make(0.01, None, 100)
    assert (o.min_spp, o.max_spp) == (16, 100)
    assert o.checkpoints() == [16, 32, 48, 64, 80, 100]
    marks = AdaptiveOptions.make(0.01, 4, 1000).checkpoints()
    assert marks[-1] == 1000 and all(b - a == max(4, a // 4) for a, b in zip(marks, marks[1:-1]))  # a quarter more
    assert AdaptiveOptions.make(0.1, None, 8).checkpoints() == [8]
    for bad, what in [((0, None, 64), "positive"), ((float("nan"), None, 64), "positive"),
                      ((0.01, 1, 64), "at least 2"), ((0.01, 65, 64), "at most max spp"),
                      ((0.01, None, 0), "max spp")]:
        with pytest.raises(ValueError, match=what):
            AdaptiveOptions.make(*bad)


def test_samples_go_where_the_noise_is(cornell, adaptive_film):
    count = adaptive_film.count
    marks = AdaptiveOptions.make(OPTS["target_error"], None, OPTS["max_spp"]).checkpoints()
    assert set(np.unique(count)) <= set(marks)
    assert count.min() < 64 and count.max() == 64, "the light and the quiet walls stop early, the noisy ones go on"
    assert adaptive_film.metadata["adaptive"] and adaptive_film.metadata["spp"] == 64
    assert adaptive_film.metadata["spp_mean"] == pytest.approx(count.mean(), abs=1e-3)
    # the pixels that stopped after the first round are those whose pooled error met the target after it
    first = sampling_renderer(cornell).render_adaptive(**{**OPTS, "max_spp": 16})
    met = pooled_error(first) <= OPTS["target_error"]
    assert met.any() and not met.all()
    np.testing.assert_array_equal(count == 16, met)


def test_a_pixel_holds_the_samples_of_a_uniform_render(cornell, adaptive_film):
    """Per pixel, the adaptive value is the uniform render's at that pixel's count: samples 0..n-1, none reused."""
    count = adaptive_film.count
    r = sampling_renderer(cornell, driver="megakernel")
    checked = 0
    for c in np.unique(count):
        uniform = r.render(spp=int(c), seed=OPTS["seed"])
        m = count == c
        np.testing.assert_allclose(adaptive_film.image[m], uniform.image[m], rtol=2e-5, atol=1e-7)
        checked += int(m.sum())
    assert checked == count.size


@pytest.mark.parametrize("driver", ["megakernel", "wavefront"])
def test_the_split_does_not_change_the_image(cornell, adaptive_film, driver):
    """Launches of 64 pixels (the megakernel) or waves of one sample per path slot (the wavefront) against whole-list
    launches: the very same image and counts."""
    whole = (adaptive_film if driver == "megakernel"
             else sampling_renderer(cornell, driver=driver).render_adaptive(**OPTS))
    split_renderer = sampling_renderer(cornell, driver=driver)
    split_renderer.launch_pixels = 64
    if driver == "wavefront":
        split_renderer.executor.slots = 100
    split = split_renderer.render_adaptive(**OPTS)
    assert split.stats.launches > whole.stats.launches
    np.testing.assert_array_equal(split.count, whole.count)
    np.testing.assert_array_equal(split.image, whole.image)


def test_both_executors_agree(cornell, adaptive_film):
    wave = sampling_renderer(cornell, driver="wavefront").render_adaptive(**OPTS)
    same = wave.count == adaptive_film.count
    assert same.mean() > 0.99   # a decision at the threshold may flip with float rounding
    np.testing.assert_allclose(wave.image[same], adaptive_film.image[same], rtol=2e-4, atol=2e-6)


def test_furnace_is_exact(tmp_path):
    """The image mean within its error of the exact 2, and per pixel against a uniform render of the same samples.
    (Per pixel against 2 with the adaptive film's own variances is no fair test: a pixel that stopped early holds
    a hundred-odd samples of a skewed estimate, whose sample variance is itself noisy.)"""
    (tmp_path / "f.xml").write_text(furnace_scene(tmp_path, "path_mis").replace('value="4"', 'value="16"'))
    r = sampling_renderer(clrender.load_scene(tmp_path / "f.xml"))
    film = r.render_adaptive(target_error=0.02, max_spp=4096, seed=11)
    assert film.count.min() > 16 and np.median(film.count) < 4096, "the stopping rule decided the pixels"
    res = compare_mean_to_value(film, 2.0)
    assert res.passed, res.message
    uniform = r.render(spp=int(round(film.count.mean())), seed=12)
    res = compare_films(film, uniform)
    assert res.passed, res.message


def test_agrees_with_a_uniform_render_of_the_same_samples(cornell, adaptive_film):
    uniform = sampling_renderer(cornell).render(spp=int(round(adaptive_film.count.mean())), seed=99)
    res = compare_films(adaptive_film, uniform)
    assert res.passed, res.message


def test_time_limit_keeps_true_counts(cornell):
    r = sampling_renderer(cornell)
    r.launch_pixels = 64
    film = r.render_adaptive(target_error=0.001, max_spp=4096, seed=1, time_limit=0.3)
    assert film.count.max() < 4096
    assert film.metadata["spp_mean"] == pytest.approx(film.count.mean(), abs=1e-3)
    assert np.all(film.image[film.count == 0] == 0)


def test_command_line(tmp_path, capsys):
    import OpenEXR

    from clrender.cli import main

    out = tmp_path / "a.exr"
    text = (SCENES / "cornell" / "cornell_path_mis.xml").read_text().replace('"256"', '"16"')
    scene = tmp_path / "cornell" / "small.xml"   # beside the original's meshes
    scene.parent.mkdir()
    for f in (SCENES / "cornell").iterdir():
        if f.is_dir():
            (scene.parent / f.name).symlink_to(f)
    scene.write_text(text)
    scene = str(scene)
    assert main(["render", scene, "-o", str(out), "-q", "--target-error", "0.2", "--max-spp", "20", "--min-spp",
                 "4"]) == 0
    with OpenEXR.File(str(out)) as f:
        count = np.asarray(f.channels()["count"].pixels)
        assert f.header()["clrender.adaptive"] == "True"
    assert count.min() >= 4 and count.max() <= 20 and count.min() < count.max()
    for extra, said in [(["--adaptive", "--sample-range", "0:16"], "--sample-range"),
                        (["--max-spp", "16"], "add --adaptive"),
                        (["--allocation", "relmse"], "add --adaptive"),
                        (["--adaptive", "--spp", "8", "--max-spp", "16"], "give one"),
                        (["--target-error", "-1"], "positive"),
                        (["--adaptive", "--min-spp", "1"], "at least 2")]:
        assert main(["render", scene, "-o", str(tmp_path / "b.exr"), "-q", *extra]) == 2
        assert said in capsys.readouterr().err


def test_ctrl_c_stops_after_the_launch_in_flight(cornell):
    """A Ctrl-C during the second round: the render stops after the launch in flight, marked interrupted, each pixel
    with the samples it really got (64-pixel launches, so the round is cut part-way)."""
    import os
    import signal

    r = sampling_renderer(cornell)
    r.launch_pixels = 64

    def press(rnd, mark, active):
        if rnd == 1:
            os.kill(os.getpid(), signal.SIGINT)

    film = r.render_adaptive(target_error=0.001, max_spp=64, seed=1, on_round=press)
    assert film.metadata["interrupted"] and film.stats.interrupted
    assert set(np.unique(film.count)) == {16, 32}, "first round whole, the second cut after one launch"
    assert (film.count == 32).sum() == 64
    uniform = r.render(spp=32, seed=1)
    m = film.count == 32
    np.testing.assert_allclose(film.image[m], uniform.image[m], rtol=2e-5, atol=1e-7)


def test_relmse_allocation_relaxes_with_the_samples(cornell):
    """allocation="relmse": after the round ending at n samples a pixel stops when its pooled error is within
    E * sqrt(n / min_spp). Checked at the first two rounds against renders that stop there (same samples, same
    decisions); and its noisiest pixels get fewer samples than the "error" allocation gives them."""
    opts = dict(OPTS, allocation="relmse")
    full = sampling_renderer(cornell).render_adaptive(**opts)
    r = sampling_renderer(cornell)
    first, second = (r.render_adaptive(**{**opts, "max_spp": m}) for m in (16, 32))
    e = OPTS["target_error"]
    np.testing.assert_array_equal(full.count == 16, pooled_error(first) <= e)
    went_on = full.count > 16
    stopped_at_32 = went_on & (pooled_error(second) <= e * np.sqrt(2))
    assert stopped_at_32.any()
    np.testing.assert_array_equal(full.count[went_on] == 32, stopped_at_32[went_on])
    assert full.metadata["allocation"] == "relmse"
    plain = sampling_renderer(cornell).render_adaptive(**OPTS)
    assert full.count.sum() < plain.count.sum()


def test_python_api(cornell):
    opts = dict(target_error=OPTS["target_error"], max_spp=32, seed=OPTS["seed"])
    film = clrender.render(cornell, **opts)
    assert film.metadata["film"] == "splat"   # the default film splats (tests/test_adaptive_splat.py)
    np.testing.assert_array_equal(film.count, Renderer(cornell).render_adaptive(**opts).count)
    sampled = clrender.render(cornell, reconstruction="sampling", **opts)
    np.testing.assert_array_equal(sampled.count, sampling_renderer(cornell).render_adaptive(**opts).count)
    assert film.layers == ("count",) and "film" not in sampled.metadata
    with pytest.raises(ValueError, match="one process"):
        clrender.render(cornell, target_error=0.1, cluster="local:1")
    with pytest.raises(TypeError, match="target_error"):
        clrender.render(cornell, max_spp=8)


@pytest.fixture(scope="module")
def furnace(tmp_path_factory):
    d = tmp_path_factory.mktemp("furnace")
    (d / "f.xml").write_text(furnace_scene(d, "path_mis").replace('value="4"', 'value="16"'))
    return clrender.load_scene(d / "f.xml")


def test_the_switch_measures_the_spread_of_the_noise(cornell, furnace):
    """predicted_allocation's gain after a first round of 16 spp: about 1 in the furnace (every pixel sees the
    same walls), well above the threshold in the Cornell box (light, walls, shadowed corners); and the uniform spp
    it asks for is the one the stopping rule would spend: in the furnace, where a_p (the relative variance of one
    sample) is about the same everywhere, a / E^2 times the variance's confidence bound at that count."""
    opts = AdaptiveOptions.make(0.02, None, 4096)
    even, n = predicted_allocation(sampling_renderer(furnace).render(spp=16, seed=3), opts)
    assert even < 1.1 and even < UNIFORM_BELOW
    f = sampling_renderer(furnace).render(spp=256, seed=4)
    a = (f.variance() * 256 / (f.image.astype(np.float64) ** 2 + 1e-2)).mean()
    assert n == pytest.approx(a / 0.02 ** 2 * variance_bound(n), rel=0.15)
    uneven, _ = predicted_allocation(sampling_renderer(cornell).render(spp=16, seed=3), opts)
    assert uneven > UNIFORM_BELOW + 0.05


def test_even_noise_finishes_as_a_uniform_render(furnace):
    """In the furnace the render switches after its first round and its image is the uniform render's at the spp
    it went to, every pixel at that count; metadata say so. Cut into small launches, the same."""
    r = sampling_renderer(furnace)
    film = r.render_adaptive(target_error=0.05, max_spp=4096, seed=11)
    m = film.metadata
    assert m["uniform_after"] == 16 and m["predicted_gain"] < UNIFORM_BELOW
    n = m["uniform_spp"]
    assert 16 < n < 4096 and np.all(film.count == n) and m["spp"] == n
    assert m["rounds"] == len([c for c in AdaptiveOptions.make(0.05, None, 4096).checkpoints() if c < n]) + 1
    uniform = r.render(spp=n, seed=11)
    np.testing.assert_allclose(film.image, uniform.image, rtol=2e-5, atol=1e-7)
    small = sampling_renderer(furnace)
    small.launch_pixels = 8
    cut = small.render_adaptive(target_error=0.05, max_spp=4096, seed=11)
    assert cut.stats.launches > film.stats.launches
    np.testing.assert_array_equal(cut.image, film.image)


def test_uneven_noise_stays_adaptive(cornell, adaptive_film):
    assert "uniform_after" not in adaptive_film.metadata
    assert len(np.unique(adaptive_film.count)) > 2


def test_without_the_switch_the_stopping_rule_keeps_the_furnace_exact(furnace):
    film = sampling_renderer(furnace).render_adaptive(target_error=0.02, max_spp=4096, seed=11, uniform_below=0)
    assert "uniform_after" not in film.metadata and film.count.min() < film.count.max()
    res = compare_mean_to_value(film, 2.0)
    assert res.passed, res.message


def test_command_line_says_when_it_went_uniform(tmp_path, capsys):
    from clrender.cli import main

    (tmp_path / "f.xml").write_text(furnace_scene(tmp_path, "path_mis").replace('value="4"', 'value="16"'))
    scene = str(tmp_path / "f.xml")
    out = str(tmp_path / "f.exr")
    assert main(["render", scene, "-o", out, "-q", "--target-error", "0.05", "--max-spp", "1024"]) == 0
    assert "even noise: uniform from 16 spp" in capsys.readouterr().err
    assert main(["render", scene, "-o", out, "-q", "--target-error", "0.05", "--max-spp", "1024",
                 "--always-adaptive"]) == 0
    assert "even noise" not in capsys.readouterr().err
    assert main(["render", scene, "-o", out, "-q", "--always-adaptive"]) == 2
    assert "add --adaptive" in capsys.readouterr().err


def test_the_few_pixels_test_is_the_whole_images(cornell, adaptive_film):
    """pooled_error_at (the late rounds' test of their few pixels) gives pooled_error's very values, at the border
    and inside."""
    from clrender.adaptive import pooled_error_at

    h, w = adaptive_film.count.shape
    full = pooled_error(adaptive_film).reshape(-1)
    pixels = np.array([0, w - 1, w, 5 * w + 7, h * w - 1, h * w - w, 17 * w + 16, 5 * w + 8])
    np.testing.assert_array_equal(pooled_error_at(adaptive_film, pixels), full[pixels])
    np.testing.assert_array_equal(pooled_error_at(adaptive_film, np.arange(h * w)), full)


def test_next_counts_predict_the_checkpoint_that_meets_the_bound():
    """next_counts: the pooled error squared is S + F (the share that falls as vb(n) / n as the pixel and its
    going-on neighbours get samples, and the stopped neighbours' share); the count it returns is the first checkpoint
    at which the model meets the allocation's bound, within the next checkpoint .. twice the samples; where the
    stopped neighbours alone miss the bound, the cap."""
    from clrender.adaptive import MAX_ROUND_GROWTH, next_counts

    rng = np.random.default_rng(1)
    for allocation in ("error", "relmse"):
        opts = AdaptiveOptions.make(0.1, None, 4096, allocation=allocation)
        marks = np.array(opts.checkpoints())
        c = rng.choice(marks[:-3], 400)
        e2 = 0.01 * (allocation == "error" or c / 16.0)   # the bound squared at c
        S = e2 * rng.uniform(0.5, 3.0, 400)
        F = e2 * rng.uniform(0.0, 0.8, 400)
        t = next_counts(c, S, F, opts)

        def meets(n, m):
            """Whether the model's pooled error squared at n samples meets the bound, for the pixels of mask m."""
            bound2 = 0.01 if allocation == "error" else 0.01 * n / 16.0
            return F[m] + S[m] * c[m] / n * variance_bound(n) / variance_bound(c[m]) <= bound2 * (1 + 1e-9)

        lo = marks[np.searchsorted(marks, c, side="right")]                     # the next checkpoint
        hi = np.maximum(lo, marks[np.searchsorted(marks, MAX_ROUND_GROWTH * c, side="right") - 1])
        assert np.all(np.isin(t, marks)) and np.all((lo <= t) & (t <= hi))
        inside = (t > lo) & (t < hi)
        assert inside.sum() > 10, "the prediction, not only its limits, decided some"
        assert np.all(meets(t[inside], inside))
        before = marks[np.searchsorted(marks, t[inside]) - 1]
        assert not np.any(meets(before, inside)), "the first checkpoint that meets it, not a later one"
        capped = (t == hi) & (t > lo)
        assert capped.any() and not np.any(meets(marks[np.searchsorted(marks, t[capped]) - 1], capped)), \
            "the cap only where less does not meet the bound"
    # stopped neighbours alone above the bound: no count meets it, the pixel doubles
    opts = AdaptiveOptions.make(0.1, None, 4096)
    np.testing.assert_array_equal(next_counts([64, 125], [1e-4, 1e-4], [0.011, 0.02], opts), [125, 243])


def test_spans_launches_are_the_grouped_launches(cornell):
    """The megakernel's render_spans (each pixel with its own samples in one launch) sums each pixel's samples as
    one list launch per distinct span does (the wavefront's and the feature AOVs' way): the very same image and
    counts, bit for bit; the rounds skip checkpoints (fewer rounds than checkpoints reached)."""
    opts = dict(target_error=0.05, max_spp=1024, seed=3)
    spans = sampling_renderer(cornell, driver="megakernel")
    film = spans.render_adaptive(**opts)
    grouped = sampling_renderer(cornell, driver="megakernel")
    grouped.executor.spans = False
    same = grouped.render_adaptive(**opts)
    np.testing.assert_array_equal(same.count, film.count)
    np.testing.assert_array_equal(same.image, film.image)
    assert same.stats.launches > film.stats.launches
    marks = AdaptiveOptions.make(0.05, None, 1024).checkpoints()
    reached = [m for m in marks if m <= film.count.max()]
    assert film.metadata["rounds"] < len(reached) - 2, (film.metadata["rounds"], reached)


_RUN_SPANS = """
import sys
import numpy as np
from clrender.bench import load_bench_scene
from clrender.renderer import Renderer
scene, _, _ = load_bench_scene(sys.argv[1], None, width=12, height=12)
r = Renderer(scene, device="Oclgrind", driver="megakernel")
r.launch_pixels = 64   # launches over parts of the list
film = r.render_adaptive(target_error=0.3, min_spp=2, max_spp=16, seed=1, uniform_below=0)
print("rendered", len(np.unique(film.count)), film.metadata["rounds"])
"""


@needs_oclgrind
@pytest.mark.slow
def test_spans_are_clean_under_oclgrind(tmp_path):
    """render_spans over parts of a list of pixels with unequal spans: no out-of-bounds access, no race."""
    proc, report = _run_under_oclgrind(tmp_path, [str(SCENES / "cornell" / "cornell_path_mis.xml")], _RUN_SPANS)
    assert proc.returncode == 0, proc.stderr
    counts, rounds = (int(x) for x in proc.stdout.split("rendered")[1].split())
    marks = AdaptiveOptions.make(0.3, 2, 16).checkpoints()
    assert counts >= 3 and rounds < len(marks), (proc.stdout, marks)   # rounds of unequal spans
    assert report == "", report[:4000]
