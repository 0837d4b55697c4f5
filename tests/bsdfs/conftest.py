import pytest

from clrender.testing.plugin_checks import BsdfRuns


@pytest.fixture(scope="module")
def chi2_runs(ctx, queue, request):
    """The test file's chi-square cases (`chi2_case(name) -> (row, wi, grid)` over `CASES`), each run once, when a
    test first asks for it, and Šidák-corrected over the file's `N_CHI2` (its family, plugin_checks.FAMILIES) or
    its cases; seeded with the file's `CHI2_SEED` (7)."""
    m = request.module
    return BsdfRuns(ctx, queue, m.chi2_case, getattr(m, "N_CHI2", len(m.CASES)), seed=getattr(m, "CHI2_SEED", 7))
