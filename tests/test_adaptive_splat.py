"""Adaptive sampling on the splatting film (kernels/splat.cl store_pixel / splat_resolve, SplatExecutor's store).

A splatted sample counts in its neighbours, so pixels with unequal sample counts cannot share sums: the pixel with
more samples would weigh more in the pixels between them and move every edge near a change of count. The store keeps
each pixel's splats apart and the resolve weighs them by 1 / the pixel's count. So:
- with equal counts it is the uniform splatting film (same samples, same sums up to float rounding), however the
  samples are cut into launches;
- with very unequal counts (a checkerboard of 4 and 64 spp over edges and highlights) every pixel still converges to
  the uniform film's value (per-pixel z-test against a long uniform render; summing the splats unweighted, as
  the uniform film does, fails it: checked by hand on the kernel);
- its variance estimate (the uniform film's, from each splat's second moments kept in the store) matches the
  spread of independent renders with unequal counts too;
- an adaptive render splats, is deterministic however its rounds are cut, is exact in a closed furnace and agrees
  per pixel with a uniform render; where the store would not fit the device, an auto film samples the filter.
"""
import numpy as np
import pytest

import clrender
from clrender.adaptive import AdaptiveOptions
from clrender.executors import DriverError
from clrender.loader import load_scene
from clrender.renderer import Renderer
from clrender.testing.stats import compare_mean_to_value, compare_to_reference

from analytic_scenes import furnace_scene
from test_splat import scene_xml

RES = 24


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("adaptive_splat") / "scene.xml"
    path.write_text(scene_xml(res=RES))
    return load_scene(path)


@pytest.fixture(scope="module")
def renderer(scene):
    r = Renderer(scene)
    assert r.splat
    return r


def stored(r, seed, spans=None, batches=((0, 16),), launch_pixels=None):
    """A film of samples sent to the store: every pixel through range launches (`batches` of (first, count)), or
    each pixel with its own span (`spans`: (n, 2) first sample and count) through one list launch."""
    import pyopencl as cl

    host, dev = r.accumulators()
    stats = r.start_stats()
    n = r.n_pixels
    pixels = cl.Buffer(r.ctx, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR,
                       hostbuf=np.arange(n, dtype=np.uint32))
    r.executor.warm_list(pixels)
    step = launch_pixels or n
    if spans is None:
        for first, count in batches:
            for off in range(0, n, step):
                r.launch(off, min(step, n - off), first, count, seed)
        done = sum(c for _, c in batches)
    else:
        d_spans = cl.Buffer(r.ctx, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR,
                            hostbuf=np.ascontiguousarray(spans, np.uint32))
        for off in range(0, n, step):
            r.executor.launch_spans(off, min(step, n - off), pixels, d_spans, seed)
        done = int(np.max(np.asarray(spans)[:, 0] + np.asarray(spans)[:, 1]))
    return r._film(done, seed, 0, stats, host, dev, 0, n)


def agrees(film, reference, spp):
    """Per pixel against a long uniform render, the film's variance at least what the reference predicts for its
    count and its neighbours' mean: at 4 spp a pixel by the horizon may have drawn no sample of the dark side
    (empirical spread 20 times its own variance estimate)."""
    return compare_to_reference(film, reference.image, np.sqrt(reference.variance()), ref_samples=spp)


def test_equal_counts_are_the_uniform_splatting_film(renderer):
    uniform = renderer.render(spp=16, seed=3)
    n = renderer.n_pixels
    for film in (stored(renderer, 3, batches=((0, 5), (5, 5), (10, 6)), launch_pixels=64),
                 stored(renderer, 3, spans=np.tile([0, 16], (n, 1)))):
        np.testing.assert_allclose(film.image, uniform.image, rtol=2e-5, atol=2e-6)
        np.testing.assert_array_equal(film.count, uniform.count)
        # the same variance estimate as the uniform film's (the store keeps each splat's second moments)
        np.testing.assert_allclose(film.variance(), uniform.variance(), rtol=1e-3, atol=1e-7 * film.image.max() ** 2)
        assert film.metadata["film"] == "splat"


SHARP = f"""<scene version="3.0.0">
  <integrator type="direct"/>
  <sensor type="perspective">
    <float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0, 0, -4" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{RES}"/><integer name="height" value="{RES}"/></film>
  </sensor>
  <shape type="rectangle">
    <transform name="to_world"><rotate y="1" angle="180"/><scale value="2"/></transform>
    <emitter type="area"><texture type="checkerboard" name="radiance">
      <rgb name="color0" value="1"/><rgb name="color1" value="0.02"/>
      <transform name="to_uv"><rotate z="1" angle="17"/><scale value="5"/></transform></texture></emitter></shape>
</scene>
"""


def test_unequal_counts_keep_every_pixel_unbiased(tmp_path):
    """A checkerboard of 2 x 2 blocks of 4 and 1024 spp, so that most pixels' filter footprints hold both counts, over
    a light textured with a tilted checkerboard seen head on: sharp edges whose only noise is where the samples
    land in their pixels. Summing the splats without weighing each pixel by 1 / its count moves those edges
    (worst z 21.7 when tried)."""
    (tmp_path / "sharp.xml").write_text(SHARP)
    r = Renderer(load_scene(tmp_path / "sharp.xml"))
    y, x = np.divmod(np.arange(r.n_pixels), RES)
    counts = np.where((x // 2 + y // 2) % 2 == 0, 4, 1024)
    film = stored(r, 7, spans=np.stack([np.zeros_like(counts), counts], axis=-1))
    np.testing.assert_array_equal(film.count.reshape(-1), counts)
    res = agrees(film, r.render(spp=4096, seed=8), 4096)
    assert res.passed, res.message


def test_its_variance_is_the_spread_of_independent_renders(renderer):
    y, x = np.divmod(np.arange(renderer.n_pixels), RES)
    counts = np.where(x < RES // 2, 8, 32)
    spans = np.stack([np.zeros_like(counts), counts], axis=-1)
    films = [stored(renderer, 100 + s, spans=spans) for s in range(16)]
    images = np.array([f.image for f in films], np.float64)
    spread = images.var(axis=0, ddof=1)
    estimate = np.mean([f.variance() for f in films], axis=0)
    noisy = spread > 1e-6 * images.mean() ** 2
    assert noisy.mean() > 0.5
    ratio = estimate[noisy].mean() / spread[noisy].mean()
    assert 0.8 < ratio < 1.5, ratio


OPTS = dict(target_error=0.04, max_spp=64, seed=5)


@pytest.fixture(scope="module")
def adaptive_film(renderer):
    return renderer.render_adaptive(**OPTS, uniform_below=0)


def test_an_adaptive_render_splats_where_the_noise_is(adaptive_film):
    assert adaptive_film.metadata["film"] == "splat" and adaptive_film.metadata["adaptive"]
    marks = AdaptiveOptions.make(OPTS["target_error"], None, OPTS["max_spp"]).checkpoints()
    assert set(np.unique(adaptive_film.count)) <= set(marks)
    assert adaptive_film.count.min() < 64 and adaptive_film.count.max() == 64


def test_the_split_does_not_change_the_image(scene, adaptive_film):
    r = Renderer(scene)
    r.launch_pixels = 64
    split = r.render_adaptive(**OPTS, uniform_below=0)
    assert split.stats.launches > adaptive_film.stats.launches
    np.testing.assert_array_equal(split.count, adaptive_film.count)
    np.testing.assert_array_equal(split.image, adaptive_film.image)


def test_agrees_with_a_uniform_render(renderer, adaptive_film):
    res = agrees(adaptive_film, renderer.render(spp=512, seed=99), 512)
    assert res.passed, res.message


def test_furnace_is_exact(tmp_path):
    (tmp_path / "f.xml").write_text(furnace_scene(tmp_path, "path_mis").replace('value="4"', 'value="16"'))
    r = Renderer(clrender.load_scene(tmp_path / "f.xml"), reconstruction="splat")
    film = r.render_adaptive(target_error=0.02, max_spp=4096, seed=11, uniform_below=0)
    assert film.metadata["film"] == "splat"
    assert film.count.min() >= 16 and np.median(film.count) < 4096, "the stopping rule decided the pixels"
    res = compare_mean_to_value(film, 2.0)
    assert res.passed, res.message


def test_a_store_too_large_for_the_device(scene, monkeypatch):
    monkeypatch.setattr(Renderer, "store_fits", lambda self: False)
    film = Renderer(scene).render_adaptive(target_error=0.2, min_spp=4, max_spp=8, seed=1)
    assert "film" not in film.metadata and film.count.min() >= 4   # auto: the filter-sampling film
    with pytest.raises(DriverError, match="--reconstruction sampling"):
        Renderer(scene, reconstruction="splat").render_adaptive(target_error=0.2, max_spp=8)


def test_even_noise_finishes_as_the_uniform_splatting_film(tmp_path):
    """The switch to uniform sampling (a closed furnace's even noise): the first round's store becomes the film's
    sums and passes of the uniform film add the rest, so the image, counts and variances are a uniform render's."""
    (tmp_path / "f.xml").write_text(furnace_scene(tmp_path, "path_mis").replace('value="4"', 'value="16"'))
    r = Renderer(clrender.load_scene(tmp_path / "f.xml"), reconstruction="splat")
    film = r.render_adaptive(target_error=0.02, max_spp=256, seed=4)
    assert film.metadata["uniform_after"] == 16 and film.metadata["film"] == "splat"
    uniform = r.render(spp=film.metadata["uniform_spp"], seed=4)
    np.testing.assert_array_equal(film.count, uniform.count)
    np.testing.assert_allclose(film.image, uniform.image, rtol=2e-5)
    np.testing.assert_allclose(film.variance(), uniform.variance(), rtol=1e-3, atol=1e-7 * film.image.max() ** 2)


def test_a_time_limit_keeps_true_counts(renderer, tmp_path):
    """A time limit stops an adaptive splatting render between launches, in its rounds and in its uniform rest after
    the switch, with each pixel's true count (the uniform rest: one count for all)."""
    film = renderer.render_adaptive(target_error=0.001, max_spp=4096, seed=1, time_limit=0.3, uniform_below=0)
    assert film.metadata["film"] == "splat" and film.count.max() < 4096
    assert film.metadata["spp_mean"] == pytest.approx(film.count.mean(), abs=1e-3)
    (tmp_path / "f.xml").write_text(furnace_scene(tmp_path, "path_mis").replace('value="4"', 'value="16"'))
    r = Renderer(clrender.load_scene(tmp_path / "f.xml"), reconstruction="splat")
    film = r.render_adaptive(target_error=0.0005, max_spp=1 << 20, seed=1, time_limit=0.5)
    assert film.metadata["uniform_after"] == 16
    assert len(np.unique(film.count)) == 1 and 16 < film.count.max() < film.metadata["uniform_spp"]


def test_the_store_counts_in_the_device_memory(scene):
    r = Renderer(scene)
    before = r.device_memory_bytes()
    r.render_adaptive(target_error=0.2, min_spp=4, max_spp=8, seed=1)
    assert r.device_memory_bytes() - before >= sum(r.executor.store_buffer_bytes())
