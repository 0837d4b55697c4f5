import pytest

from clrender.testing.kernels import plugin_set, programs_holding
from clrender.testing.plugin_checks import BsdfRuns


@pytest.fixture(scope="module")
def chi2_runs(ctx, queue, request):
    """The test file's chi-square cases (`chi2_case(name) -> (row, wi, grid)` over `CASES`), each run once, when a
    test first asks for it, and Šidák-corrected over the file's `N_CHI2` (its family, plugin_checks.FAMILIES) or
    its cases; seeded with the file's `CHI2_SEED` (7)."""
    m = request.module
    return BsdfRuns(ctx, queue, m.chi2_case, getattr(m, "N_CHI2", len(m.CASES)), seed=getattr(m, "CHI2_SEED", 7))


@pytest.fixture(scope="module", autouse=True)
def one_program(request):
    """The file's tests share one test program: the plugins its `PROGRAM` names (keywords of
    clrender.testing.kernels.plugin_set), which each program for the file's rows also holds. Without it, each
    subset of plugins that some rows use compiles its own program (seconds each on 2 cores, cold)."""
    spec = getattr(request.module, "PROGRAM", None)
    if spec is None:
        yield
        return
    with programs_holding(plugin_set(**spec)):
        yield
