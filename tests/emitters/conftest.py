# the emitters' device program, their test scenes and environment maps: fixtures
from .emitter_common import envmaps, kernels, scenes  # noqa: F401
