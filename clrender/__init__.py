"""clrender: a physically based path tracer whose rendering runs as portable OpenCL C kernels.

    import clrender
    scene = clrender.load_scene("scenes/cornell/cornell_path_mis.xml")
    film = clrender.render(scene, spp=64, seed=0)      # PoCL CPU by default; device="gpu" or an index
    film.image            # (H, W, 3) float32 linear radiance
    film.write_exr("cornell.exr"); film.write_png("cornell.png")
"""
__version__ = "0.1.0"


def load_scene(path, nori_dialect=None, **defines):
    """Load a Nori XML scene file (``defines`` fill ``$name`` placeholders).

    ``nori_dialect``: "upstream" (wjakob/nori, EPFL; the default) or "eth" (ETH Zürich, Dartmouth 2015):
    they differ in the camera's x direction and in rotate axes. None reads $CLRENDER_NORI_DIALECT."""
    from .loader import load_scene as _load

    return _load(path, nori_dialect=nori_dialect, **defines)


def render(scene, spp=None, seed=0, device=None, time_limit=None, progress=False):
    """Render a loaded scene on an OpenCL device and return its Film."""
    from .renderer import render as _render

    return _render(scene, spp=spp, seed=seed, device=device, time_limit=time_limit, progress=progress)


__all__ = ["load_scene", "render", "__version__"]
