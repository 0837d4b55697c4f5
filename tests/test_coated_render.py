"""Mixtures of delta and smooth lobes in the integrators (default run; the full twin comparisons are slow tests).

A plastic (a delta coating over a diffuse base), a mask (a pass-through over its child) and a blend with a delta
child have both kinds of lobes. The integrators (kernels/integrators/*.h) must then sample emitters at the vertex
(bsdf_is_delta is false: only BSDFs with no smooth lobe skip it), evaluate the smooth part there (bsdf_eval/pdf hold
only that), and count emission found after a delta sample (q.measure == MEASURE_DISCRETE) with full weight and no
MIS. Each of path_mats (BSDF sampling only: right whatever the flags), path_ems (emitter sampling at every
vertex with a smooth lobe, emission only after delta samples) and path_mis must give Mitsuba's image of the twin
scenes: a mixture treated as delta loses the light emitter sampling should have found (path_ems, path_mis), one
treated as smooth without counting its delta samples' emission loses the coating's reflections (path_ems)."""
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent / "mitsuba"


@pytest.mark.slow   # six renders at the twins' precision (~2 min): run by .ci/run with the other slow suites
@pytest.mark.parametrize("integrator", ["path_mats", "path_ems", "path_mis"])
@pytest.mark.parametrize("name", ["coated_plastics", "composites"])
def test_mixed_delta_lobes_in_every_path_integrator(name, integrator):
    import clrender
    from clrender.scene.registry import instantiate
    from clrender.testing.stats import compare_image_means

    with np.load(HERE / "refs" / f"{name}.npz") as z:
        mean, stderr, ref_spp = z["mean"], z["stderr"], int(z["spp"])
    scene = clrender.load_scene(HERE / "scenes" / f"{name}.xml", spp=48)
    scene.integrator = instantiate("integrator", integrator, {})
    film = clrender.render(scene, seed=3)
    result = compare_image_means(film, mean, stderr, ref_spp)
    assert result.passed, (f"{name} with {integrator}: {result.message}; clrender "
                           f"{film.image.mean(axis=(0, 1)).round(4)}, Mitsuba {mean.mean(axis=(0, 1)).round(4)}")
