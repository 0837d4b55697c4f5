from .emitter_common import kernels, scenes  # noqa: F401  (the emitters' device program and test scenes: fixtures)
