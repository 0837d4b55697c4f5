import os
from pathlib import Path

import pytest

# Keep PoCL's kernel cache inside the work tree (CI, and so tests never touch ~/.cache).
os.environ.setdefault("POCL_CACHE_DIR", str(Path(__file__).resolve().parents[1] / ".pocl-cache"))
# Likewise the OpenCL vendors folder clrender writes when the intel-cpu extra is installed.
os.environ.setdefault("CLRENDER_ICD_DIR",
                      str(Path(__file__).resolve().parents[1] / ".pocl-cache" / "opencl-vendors"))

import clrender.plugins  # noqa: E402,F401  (the test-suite, like the CLI, assembles the application)


@pytest.fixture(scope="session")
def cl_env():
    """(context, queue) on the default device (PoCL CPU)."""
    from clrender.device.context import get_context

    return get_context(None)


@pytest.fixture(scope="session")
def ctx(cl_env):
    return cl_env[0]


@pytest.fixture(scope="session")
def queue(cl_env):
    return cl_env[1]


def pytest_configure(config):
    # Read by tests/test_plugin_coverage.py (from the source, without importing the test files).
    config.addinivalue_line("markers", "plugin(name, aspect): the test covers plugin `name`'s `aspect` "
                                       "(sampling, eval or render); see clrender/testing/plugin_checks.py")
