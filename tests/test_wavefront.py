"""The wavefront driver (kernels/wavefront.cl, clrender/executors.py) against the megakernel: both run the same stage
functions (kernels/integrators/path.h) and draw the same random numbers, so every path integrator gives the same
image with either, pixel for pixel, up to float rounding. Rendered over a band of pixels to keep the suite short.
Also: the image does not depend on how many paths a wave holds, and the driver is refused where it cannot run."""
from pathlib import Path

import numpy as np
import pytest

import clrender
import clrender.plugins  # noqa: F401  (registers the plugins)
from clrender.renderer import Renderer
from clrender.scene.registry import instantiate

SCENES = Path(__file__).resolve().parents[1] / "scenes"
TAGS = {bool: "boolean", int: "integer", str: "string", float: "float"}

# (scene, Mitsuba integrator replacing the scene's, its properties)
CASES = [
    ("cornell/cornell_path_mats.xml", None, {}),
    ("cornell/cornell_path_ems.xml", None, {}),
    ("cornell/cornell_path_mis.xml", None, {}),
    ("glass/glass_path_mis.xml", None, {}),
    ("furnace/furnace_env_path_mis.xml", None, {}),
    ("mitsuba/showcase.xml", None, {}),
    ("mitsuba/showcase.xml", "path", {"hide_emitters": True}),
    ("mitsuba/showcase.xml", "path", {"max_depth": 2}),
    ("mitsuba/showcase.xml", "volpath", {"hide_emitters": True, "max_depth": 4}),
    ("mitsuba/showcase.xml", "volpathmis", {}),
    ("mitsuba/showcase.xml", "prb", {"max_depth": 3, "rr_depth": 1}),
    ("cornell/cornell_path_mis.xml", "path", {"max_depth": 0}),
]


def load(scene, integrator=None, props=None):
    s = clrender.load_scene(SCENES / scene)
    if integrator is not None:
        s.integrator = instantiate("integrator", integrator, {k: (TAGS[type(v)], v) for k, v in props.items()},
                                   fmt="mitsuba")
    return s


def band(scene, rows=6):
    """A band of rows through the middle of the image."""
    first = (scene.height // 2 - rows // 2) * scene.width
    return first, first + rows * scene.width


def render(scene, driver, spp=3, seed=7, **kw):
    # the wavefront samples the filter; the megakernel then does too (its default film splats)
    return Renderer(scene, driver=driver, reconstruction="sampling").render(spp=spp, seed=seed, pixels=band(scene),
                                                                             **kw)


@pytest.mark.parametrize("scene,integrator,props", CASES,
                         ids=[f"{Path(s).stem}-{i or 'own'}-{'-'.join(f'{k}={v}' for k, v in p.items())}"
                              for s, i, p in CASES])
def test_wavefront_gives_the_megakernel_image(scene, integrator, props):
    s = load(scene, integrator, props)
    mega, wave = render(s, "megakernel"), render(s, "wavefront")
    p0, p1 = band(s)
    a, b = mega.image.reshape(-1, 3)[p0:p1], wave.image.reshape(-1, 3)[p0:p1]
    if props.get("max_depth") == 0:
        assert np.all(a == 0) and np.all(b == 0)
    else:
        assert a.mean() > 1e-3, "the band must show something for the comparison to mean anything"
    # the same samples: the same value per pixel up to float rounding (contractions, summation of the same terms)
    np.testing.assert_allclose(b, a, rtol=2e-4, atol=2e-6)
    assert wave.metadata["spp"] == mega.metadata["spp"]
    np.testing.assert_array_equal(wave.dropped.reshape(-1)[p0:p1], mega.dropped.reshape(-1)[p0:p1])


def test_the_wave_size_does_not_change_the_image():
    """A wave of a few hundred paths (several waves per pass, each pixel's samples split across them) gives the very
    image of one wave holding the whole pass: the pixel sums are formed in sample order either way."""
    s = load("cornell/cornell_path_mis.xml")
    whole_renderer = Renderer(s, driver="wavefront")
    whole = whole_renderer.render(spp=5, seed=7, pixels=band(s))
    split_renderer = Renderer(s, driver="wavefront")
    split_renderer.executor.slots = 700   # waves of one sample per pixel: five waves per pass
    split = split_renderer.render(spp=5, seed=7, pixels=band(s))
    assert split_renderer.executor.waves == 5 > whole_renderer.executor.waves
    np.testing.assert_array_equal(split.image, whole.image)


def test_passes_and_time_limits_work_with_the_wavefront():
    """Two renders of samples 0-1 and 2-4 add up to the render of 0-4 (sample numbering, per-pass flush)."""
    s = load("cornell/cornell_path_mis.xml")
    r = Renderer(s, driver="wavefront")
    p = band(s)
    a = r.render(spp=2, seed=3, pixels=p)
    b = r.render(spp=3, seed=3, pixels=p, start_sample=2)
    both = r.render(spp=5, seed=3, pixels=p)
    np.testing.assert_allclose(a.sum_wl + b.sum_wl, both.sum_wl, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(a.sum_w + b.sum_w, both.sum_w, rtol=1e-5, atol=1e-6)
    np.testing.assert_array_equal(a.count + b.count, both.count)
    timed = r.render(spp=10_000, seed=3, pixels=p, time_limit=0.5)
    assert 1 <= timed.metadata["spp"] < 10_000


def test_auto_picks_the_megakernel_and_wavefront_refuses_other_integrators():
    s = load("cornell/cornell_path_mis.xml")
    assert Renderer(s).driver == "megakernel"
    direct = load("cornell/cornell_direct_mis.xml")
    with pytest.raises(ValueError, match="wavefront driver runs the path integrators"):
        Renderer(direct, driver="wavefront")
    with pytest.raises(ValueError, match="unknown driver"):
        Renderer(s, driver="fast")


# The wavefront's other forms, measured in benchmarks/README.md ("third step") and opt-in by build defines: path state
# in structure-of-arrays buffers (WF_SOA), and the shade stage over WF_LANES paths per work-item in a loop that LLVM's
# loop vectoriser widens (WF_LANES; needs the vec3 passed in memory). Both must give the megakernel's image.
LAYOUTS = [{"WF_SOA": None}, {"WF_LANES": 4, "CLR_VEC3_PASS_IN_MEMORY": None},
           {"WF_LANES": 4, "CLR_VEC3_PASS_IN_MEMORY": None, "WF_SOA": None}]


@pytest.mark.slow
@pytest.mark.parametrize("scene", ["cornell/cornell_path_mis.xml", "glass/glass_path_mis.xml"])
@pytest.mark.parametrize("defines", LAYOUTS, ids=lambda d: "+".join(d))
def test_every_layout_of_the_wavefront_gives_the_megakernel_image(scene, defines):
    s = load(scene)
    p0, p1 = band(s, rows=5)   # an odd number of paths: shade launches whose last work-item has idle lanes
    mega = Renderer(s, driver="megakernel", reconstruction="sampling").render(spp=3, seed=7, pixels=(p0, p1))
    wave = Renderer(s, driver="wavefront", defines=defines).render(spp=3, seed=7, pixels=(p0, p1))
    a, b = mega.image.reshape(-1, 3)[p0:p1], wave.image.reshape(-1, 3)[p0:p1]
    assert a.mean() > 1e-3
    np.testing.assert_allclose(b, a, rtol=2e-4, atol=2e-6)
    np.testing.assert_array_equal(wave.dropped.reshape(-1)[p0:p1], mega.dropped.reshape(-1)[p0:p1])
