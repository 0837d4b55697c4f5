"""The splatting film (kernels/splat.cl, Renderer(reconstruction="splat")): each sample, placed uniformly in its
pixel, weighted into every pixel within the filter's radius, as Mitsuba's and Nori's films do.

It must converge to the filter-sampling film's image (render.cl: the same expected image), estimate its own
variance (Film.variance from the sums of w^2 L and w^2), have less noise than filter sampling with a wide filter
(the point of it), give the same sums whether the pixels are rendered as one film, in bands (a cluster's tasks:
each band renders its halo's samples too) or as sample ranges merged later, and drop NaN/Inf samples. With a
Mitsuba film's sample_border it draws samples in a border around the window too (kernels/splat.cl CLR_SPLAT_BORDER),
and its edge pixels then agree with filter sampling's, which lets the filter reach past the window.
"""
import numpy as np
import pytest

from clrender.executors import DriverError
from clrender.loader import load_scene
from clrender.parts import merge_parts, read_part, write_part
from clrender.renderer import Renderer
from clrender.testing.stats import neighbourhood_mean, sidak

RES = 24


def scene_xml(filter_xml: str = "", res: int = RES, shapes: str = "") -> str:
    """A glossy sphere and a textured floor under a sky and a small bright light: edges, highlights and a
    gradient, so pixels differ from their neighbours (Mitsuba format: samples stay inside the window, as the
    splatting film's do, so the two films agree at the border too)."""
    return f"""<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0, 1.2, -4" target="0, 0.2, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{res}"/><integer name="height" value="{res}"/>{filter_xml}</film>
  </sensor>
  <emitter type="constant"><rgb name="radiance" value="0.3, 0.4, 0.5"/></emitter>
  <shape type="sphere"><point name="center" x="0" y="0.5" z="0"/><float name="radius" value="0.6"/>
    <bsdf type="roughconductor"><float name="alpha" value="0.15"/></bsdf></shape>
  <shape type="sphere"><point name="center" x="1.5" y="2.5" z="-1"/><float name="radius" value="0.15"/>
    <emitter type="area"><rgb name="radiance" value="40, 35, 30"/></emitter></shape>
  <shape type="rectangle">
    <transform name="to_world"><rotate x="1" angle="-90"/><scale value="5"/><translate y="-0.1"/></transform>
    <bsdf type="diffuse"><texture type="checkerboard" name="reflectance">
      <transform name="to_uv"><scale value="6"/></transform></texture></bsdf></shape>{shapes}
</scene>
"""


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    path = tmp_path_factory.mktemp("splat") / "scene.xml"
    path.write_text(scene_xml())
    return load_scene(path)


@pytest.fixture(scope="module")
def renderers(scene):
    return {m: Renderer(scene, reconstruction=m) for m in ("splat", "sampling")}


BORDER = '<boolean name="sample_border" value="true"/>'
#: two tall panels, brighter than the sky, facing the camera just outside the window's left and right edges (the
#: window's half-width at the target's distance is sqrt(17) tan 20 deg = 1.50; the panels span 1.52 to 2.12 from
#: its centre): only samples placed outside the window see them, so with sample_border the outer columns take
#: their light
EDGE_PANELS = "".join(f"""
  <shape type="rectangle"><transform name="to_world"><scale x="0.3" y="1.6"/>
    <lookat origin="{x}, 0.2, 0" target="{x}, 1.2, -4" up="0, 1, 0"/></transform>
    <emitter type="area"><rgb name="radiance" value="2, 2, 2"/></emitter></shape>""" for x in (-1.82, 1.82))


@pytest.fixture(scope="module")
def border_renderers(tmp_path_factory):
    """The two films of the scene with Mitsuba's sample_border."""
    path = tmp_path_factory.mktemp("splat_border") / "scene.xml"
    path.write_text(scene_xml(BORDER, shapes=EDGE_PANELS))
    scene = load_scene(path)
    return {m: Renderer(scene, reconstruction=m) for m in ("splat", "sampling")}


def test_auto_splats_a_wide_filter_and_not_a_box(scene, renderers, tmp_path):
    assert renderers["splat"].splat and not renderers["sampling"].splat
    assert Renderer(scene).splat   # Mitsuba's default Gaussian
    box = tmp_path / "box.xml"
    box.write_text(scene_xml('<rfilter type="box"/>', res=4))
    assert not Renderer(load_scene(box)).splat   # a box reaches no neighbour: nothing to share
    with pytest.raises(DriverError, match="megakernel"):
        Renderer(scene, reconstruction="splat", driver="wavefront")
    assert not Renderer(scene, driver="wavefront").splat
    border = tmp_path / "border.xml"   # Mitsuba's sample_border: samples outside the window too, splatted
    border.write_text(scene_xml(BORDER, res=4))
    r = Renderer(load_scene(border))
    assert r.splat and r.splat_border == 2 and r.executor.grid_width == 8
    assert Renderer(scene).splat_border == 0


def _assert_same_image(splat, sampling):
    """Per pixel, the two films' means over 128 spp agree within their estimated errors: z-scores whose mean
    square is 1 and whose largest stays under the Šidák bound over the pixels. A filter-sampling pixel beside
    an edge (the horizon) may have drawn no far offset across it, and then its own variance is near 0 while its
    error is not: it takes at least its 3 x 3 neighbourhood's mean variance (as stats.compare_to_reference).
    Returns the z-scores of the pixels."""
    a = splat.render(spp=128, seed=11)
    b = sampling.render(spp=128, seed=12)
    assert a.metadata["film"] == "splat" and "film" not in b.metadata
    diff = (a.image - b.image).astype(np.float64)
    var = a.variance() + b.variance()
    ok = var > 0
    assert 0.7 < np.mean(diff[ok] ** 2 / var[ok]) < 1.3, np.mean(diff[ok] ** 2 / var[ok])
    vb = b.variance()
    var = a.variance() + np.maximum(vb, neighbourhood_mean(vb))
    z = diff[ok] / np.sqrt(var[ok])
    from scipy import stats

    bound = stats.norm.isf(sidak(1e-3, z.size) / 2)
    assert np.abs(z).max() < bound, (np.abs(z).max(), bound)
    assert abs(a.image.mean() / b.image.mean() - 1) < 0.01
    out = np.zeros(diff.shape)
    out[ok] = z
    return out


def test_same_image_as_filter_sampling(renderers):
    _assert_same_image(renderers["splat"], renderers["sampling"])


def test_sample_border_same_image_as_filter_sampling(border_renderers):
    """With sample_border the edge pixels take the samples drawn outside the window too: the splatting film's
    image is filter sampling's (which reaches past the window) there as well, the light of the panels just
    outside the window included. Without the border's samples the two outer columns would be the window-clipped
    average instead (sample_border false), without the panels: gathered from the window only, their mean squared
    z-score was 4.8 (0.60 here), the whole image's 1.62 and the means' ratio 0.963 (0.995)."""
    z = _assert_same_image(border_renderers["splat"], border_renderers["sampling"])
    edge = np.r_[z[:, :2], z[:, -2:]]
    assert np.mean(edge ** 2) < 1.5, np.mean(edge ** 2)


def test_sample_border_adaptive_samples_the_filter(border_renderers):
    """Adaptive sampling's store holds the window's pixels only: with sample_border an automatic film renders
    adaptively by sampling the filter, and a splatting film asked for says why it cannot."""
    r = border_renderers["splat"]
    with pytest.raises(DriverError, match="sample_border"):
        r.render_adaptive(target_error=0.5, min_spp=2, max_spp=4)
    auto = Renderer(r.scene)
    assert auto.splat and auto.splat_border
    film = auto.render_adaptive(target_error=0.5, min_spp=2, max_spp=4)
    assert "film" not in film.metadata and np.isfinite(film.image).all() and film.image.mean() > 0


def test_variance_estimate_and_less_noise(renderers):
    """Eight renders of 16 spp per film: the splatting film's variance() predicts its pixels' spread over the
    renders, and that spread is well under half the filter-sampling film's (Mitsuba's Gaussian shares each sample
    with about three pixels), over the pixels outside the 2 % with the largest variance (the small light's rim,
    whose rare samples would decide a plain mean)."""
    spread, keep = {}, None
    for m in ("sampling", "splat"):
        films = [renderers[m].render(spp=16, seed=s) for s in range(20, 28)]
        spread[m] = np.stack([f.image.astype(np.float64) for f in films]).var(axis=0, ddof=1)
        predicted = np.mean([f.variance() for f in films], axis=0)
        if keep is None:
            keep = predicted < np.quantile(predicted, 0.98)
    ratio = spread["splat"][keep].mean() / predicted[keep].mean()
    assert 0.85 < ratio < 1.15, ratio
    assert spread["splat"][keep].mean() < 0.5 * spread["sampling"][keep].mean()


def test_bands_and_sample_ranges_give_the_whole_films_sums(renderers, tmp_path):
    """A band of rows (a cluster task) renders its halo's samples too, so its sums are the whole film's; so does
    a pass cut into chunks of rows to bound its record buffer; sample ranges merged add up to the render of their
    union; parts of the two films do not merge."""
    r = renderers["splat"]
    _assert_bands_and_chunks_add_up(r)
    film = r.render(spp=8, seed=5)
    parts = []
    for i, start in enumerate((0, 3)):
        f = r.render(spp=(3, 5)[i], seed=5, start_sample=start)
        parts.append(write_part(f, tmp_path / f"p{i}.exr", "hash", 5, start, (3, 5)[i]))
    merged = merge_parts([read_part(p) for p in parts])
    assert merged.metadata["film"] == "splat"
    np.testing.assert_allclose(merged.image, film.image, rtol=1e-4, atol=1e-6)
    v = film.variance()
    np.testing.assert_allclose(merged.variance(), v, rtol=1e-3, atol=1e-4 * v.max())
    other = renderers["sampling"].render(spp=2, seed=5, start_sample=8)
    write_part(other, tmp_path / "q.exr", "hash", 5, 8, 2)
    with pytest.raises(Exception, match="film"):
        merge_parts([read_part(p) for p in parts] + [read_part(tmp_path / "q.exr")])


def _assert_bands_and_chunks_add_up(r):
    """Bands of rows, and a pass cut into chunks of rows (each rendering its halo), give the whole film's sums."""
    whole = r.render_accumulators(spp=4, seed=5)
    n = RES * RES
    for p0, p1 in ((0, 7 * RES), (7 * RES, 13 * RES + 5), (13 * RES + 5, n)):
        band = r.render_accumulators(spp=4, seed=5, pixels=(p0, p1))
        for name in ("acc0", "acc1", "acc2", "bad"):
            np.testing.assert_allclose(band[name], whole[name][p0:p1], rtol=2e-6, atol=1e-7, err_msg=name)
    r.executor.MAX_RECORD_BYTES = r.executor.record_bytes() * 4 * RES * 6   # chunks of 2 rows and their halos
    try:
        chunked = r.render_accumulators(spp=4, seed=5)
    finally:
        del r.executor.MAX_RECORD_BYTES
    for name in ("acc0", "acc1", "acc2", "bad"):
        np.testing.assert_allclose(chunked[name], whole[name], rtol=2e-6, atol=1e-7, err_msg=name)


def test_sample_border_bands_and_chunks(border_renderers):
    """The halo of a band counts in the records' larger grid (the window and its border): bands and chunks still
    give the whole film's sums."""
    _assert_bands_and_chunks_add_up(border_renderers["splat"])


def test_nan_and_inf_samples_are_dropped_and_counted(scene):
    """A test build poisons samples 0, 5, 7, 10, ... (render.cl's CLRENDER_TEST_POISON): each pixel counts them
    as dropped, and no pixel's value is poisoned."""
    r = Renderer(scene, reconstruction="splat", defines={"CLRENDER_TEST_POISON": 1})
    f = r.render(spp=35, seed=3)
    bad = sum(1 for s in range(35) if s % 5 == 0 or s % 7 == 0)
    assert (f.dropped == bad).all() and (f.count == 35 - bad).all()
    assert np.isfinite(f.image).all() and np.isfinite(f.variance()).all() and f.image.mean() > 0


def test_command_line(tmp_path, capsys):
    """`clrender render` splats by default (the EXR header says so), adaptive renders too, samples the filter when
    asked, and refuses a splatting film where it cannot run, naming the option."""
    from clrender.cli import main
    from clrender.film import read_exr

    scene = tmp_path / "s.xml"
    scene.write_text(scene_xml(res=8))
    out = tmp_path / "o.exr"
    assert main(["render", str(scene), "-q", "--spp", "2", "-o", str(out)]) == 0
    assert read_exr(out)[1]["clrender.film"] == "splat"
    assert main(["render", str(scene), "-q", "--spp", "2", "-o", str(out), "--reconstruction", "sampling"]) == 0
    assert "clrender.film" not in read_exr(out)[1]
    assert main(["render", str(scene), "-q", "--max-spp", "4", "--target-error", "0.5", "-o", str(out)]) == 0
    assert read_exr(out)[1]["clrender.film"] == "splat"   # adaptive sampling splats too (test_adaptive_splat.py)
    capsys.readouterr()
    assert main(["render", str(scene), "-q", "--spp", "2", "-o", str(out), "--reconstruction", "splat",
                 "--driver", "wavefront"]) == 2
    assert "--driver megakernel" in capsys.readouterr().err
