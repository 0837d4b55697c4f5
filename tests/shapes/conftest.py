# the emitters' device program: the shapes are sampled through an area emitter on them
from emitters.emitter_common import kernels  # noqa: F401
