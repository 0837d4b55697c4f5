"""Emitters at the scene level and the Nori emitters' plugin checks (kernels/emitter.h; each emitter's own tests are
tests/emitters/test_<name>.py, their set-up tests/emitters/emitter_common.py): uniform choice among the emitters with
pdf = (1/N) emitter pdf, the located errors of the plugins' parameters, their flags and rows."""
import numpy as np
import pytest
from scipy import stats

from clrender.device.dispatch import flag_defines as layout_flags
from clrender.device.layout import NONE
from clrender.errors import SceneError
from clrender.loader import load_scene
from clrender.pack import pack_scene
from emitters.emitter_common import HEADER, _refs, kernels, scenes  # noqa: F401  (kernels, scenes: fixtures)


def test_scene_selection_is_uniform(scenes):
    d = scenes["three"]
    n = 60_000
    rng = np.random.default_rng(11)
    refs = _refs(rng, n, [-0.5, 0.0, -0.5], [0.5, 1.0, 0.5])
    s = d.sample(NONE, refs, rng.random((n, 3), dtype=np.float32))
    counts = np.bincount(s["emitter"], minlength=3)
    assert len(counts) == 3
    assert stats.chisquare(counts).pvalue > 1e-3, counts
    # pdf = (1/N) emitter pdf for the area and the distant disk; (1/N) for the point light (discrete)
    em = s["emitter"]
    smooth = em != 1
    np.testing.assert_allclose(s["pdf"][smooth], s["pdf_one"][smooth] / 3, rtol=2e-4)
    np.testing.assert_allclose(s["pdf_again"][smooth], s["pdf_one"][smooth] / 3, rtol=2e-4)
    np.testing.assert_allclose(s["pdf"][~smooth], 1 / 3)
    assert np.all(s["delta"][~smooth] == 1) and np.all(s["delta"][smooth] == 0)
    # weights: eval / (pdf/N) for the smooth ones, N I / d² for the point
    np.testing.assert_allclose(s["w"][smooth], s["eval"][smooth] / s["pdf"][smooth, None], rtol=2e-4, atol=1e-6)
    dist = s["dist"][~smooth]
    np.testing.assert_allclose(s["w"][~smooth] * dist[:, None] ** 2, 3 * 10 / (4 * np.pi), rtol=1e-4)


@pytest.mark.parametrize("body, message", [
    ('<emitter type="distantdisk"><color name="radiance" value="1"/><float name="thetaA" value="0"/></emitter>',
     "thetaA"),
    ('<emitter type="distantdisk"><color name="radiance" value="1"/><float name="thetaA" value="181"/></emitter>',
     "thetaA"),
    ('<emitter type="distantdisk"><color name="radiance" value="1"/></emitter>', "thetaA"),
    ('<emitter type="point"><point name="position" value="0,0,0"/></emitter>', "power"),
    ('<emitter type="point"><color name="power" value="-1"/></emitter>', "power"),
    ('<emitter type="distant"><vector name="direction" value="0,0,0"/><color name="irradiance" value="1"/></emitter>',
     "direction"),
    ('<emitter type="constant"><color name="radiance" value="1"/><float name="scale" value="2"/></emitter>',
     "scale"),
])
def test_plugin_errors(tmp_path, body, message):
    (tmp_path / "s.xml").write_text(HEADER + body + "</scene>\n")
    with pytest.raises(SceneError, match=message):
        load_scene(tmp_path / "s.xml")


def test_plugin_flags_and_rows(tmp_path):
    from clrender.emitters.constant import ConstantEmitter
    from clrender.emitters.distant import DistantEmitter
    from clrender.emitters.distantdisk import DistantDiskEmitter
    from clrender.emitters.point import PointEmitter

    assert PointEmitter.is_delta and DistantEmitter.is_delta
    assert DistantDiskEmitter.is_infinite and ConstantEmitter.is_infinite
    assert not (PointEmitter.is_infinite or ConstantEmitter.is_delta or DistantDiskEmitter.is_delta)
    (tmp_path / "s.xml").write_text(HEADER + '<emitter type="distantdisk"><color name="radiance" value="2"/>'
                                    '<float name="thetaA" value="180"/></emitter></scene>\n')
    row = pack_scene(load_scene(tmp_path / "s.xml")).emitters[0]
    from clrender.device.dispatch import tag_of

    assert row["type"] == tag_of(DistantDiskEmitter)
    assert row["flags"] == layout_flags()["EMITTER_INFINITE"]
    p = row["distantdisk"]
    np.testing.assert_allclose([p["cos_max"], p["one_minus_cos"], p["pdf"]], [-1, 2, 1 / (4 * np.pi)], rtol=1e-6,
                               atol=1e-7)
