"""Values Mitsuba 3 itself gives for its conductors and dielectrics (tests/mitsuba/bsdf_values/
conductors_dielectrics.json, written by make_bsdf_values.py there), and the two checks every such plugin's test file
runs against them: a glossy plugin's eval at fixed direction pairs, a delta plugin's sampled events."""
import functools
import json
from pathlib import Path

import numpy as np
from scipy import stats

from clrender.testing.plugin_checks import ALPHA, bsdf_pdf_eval_batch, bsdf_sample_batch, mitsuba_bsdf, sidak

VALUES = Path(__file__).resolve().parent.parent / "mitsuba" / "bsdf_values" / "conductors_dielectrics.json"
DELTA_KINDS = ("conductor", "dielectric", "thindielectric")


@functools.lru_cache(maxsize=None)
def values():
    return json.loads(VALUES.read_text())


def ref_cases(kinds):
    return [c for c in values()["cases"] if c["type"] in kinds]


def case_id(c):
    return c["type"] + "-" + "-".join(f"{k}={v[1]}" for k, v in c["props"].items())


def instance(c):
    return mitsuba_bsdf(c["type"], {k: (t, tuple(v) if t == "color" else v) for k, (t, v) in c["props"].items()})


def check_glossy_values(ctx, queue, case):
    """eval at the file's direction pairs equals Mitsuba's (its eval divided by |cos theta_o| when written)."""
    r = instance(case).pack()
    wi = np.asarray(values()["wi"])
    wo = np.asarray(values()["wo"])
    ref = np.asarray(case["f"])
    k = wo.shape[1]
    _, f = bsdf_pdf_eval_batch(ctx, queue, np.array([r]), np.repeat(wi, k, axis=0), wo.reshape(-1, 3),
                               row_index=np.zeros(len(wi) * k))
    ref = ref.reshape(-1, 3)
    assert (ref > 0).sum() > len(ref) // 4, "the reference set must exercise the lobe"
    np.testing.assert_allclose(f, ref, rtol=3e-3, atol=1e-5 * max(ref.max(), 1e-3))


def check_delta_events(ctx, queue, case):
    """For each wi: the reflection and transmission directions and weights Mitsuba samples, and how often each
    happens (Mitsuba's bs.pdf of the delta lobe; a binomial test, Šidák-corrected over every delta case of the
    file)."""
    r = instance(case).pack()
    n = 40000
    a = sidak(ALPHA, len(ref_cases(DELTA_KINDS)) * len(case["events"]))
    for wi, ev in zip(values()["wi"], case["events"]):
        wi = np.asarray(wi)
        s = bsdf_sample_batch(ctx, queue, r, wi, n, 5)
        assert np.all(s.measure == 1)
        live = np.any(s.weight != 0, axis=1)
        refl = (s.wo[:, 2] * wi[2] > 0) & live
        trans = (s.wo[:, 2] * wi[2] < 0) & live
        for label, mask in (("reflect", refl), ("transmit", trans)):
            if label not in ev:
                assert not mask.any(), f"{case['type']} {wi}: {label} where Mitsuba has none"
                continue
            e = ev[label]
            assert mask.any(), f"{case['type']} {wi}: no {label} samples"
            np.testing.assert_allclose(s.wo[mask], np.broadcast_to(e["wo"], s.wo[mask].shape), atol=2e-6)
            np.testing.assert_allclose(s.weight[mask], np.broadcast_to(e["weight"], s.weight[mask].shape),
                                       rtol=2e-5, atol=1e-7)
            np.testing.assert_allclose(s.eta[mask], e["eta"], rtol=1e-5)
            if case["type"] != "conductor" and 0 < e["prob"] < 1:
                p = stats.binomtest(int(mask.sum()), n, e["prob"]).pvalue
                assert p > a, f"{case['type']} {wi} {label}: frequency {mask.mean():.5f} vs {e['prob']:.5f}"
