"""clrender: a physically based path tracer whose rendering runs as portable OpenCL C kernels.

    import clrender
    scene = clrender.load_scene("scenes/cornell/cornell_path_mis.xml")
    film = clrender.render(scene, spp=64, seed=0)      # PoCL CPU by default; device="gpu" or an index
    film.image            # (H, W, 3) float32 linear radiance
    film.write_exr("cornell.exr"); film.write_png("cornell.png")
    film = clrender.render(scene, spp=1024, cluster="local:4")   # on Dask (clrender[cluster]): cluster.py
"""
from .version import __version__


def load_scene(path, nori_dialect=None, **defines):
    """Load a Nori XML scene file (``defines`` fill ``$name`` placeholders).

    ``nori_dialect``: "upstream" (wjakob/nori, EPFL; the default) or "eth" (ETH Zürich, Dartmouth 2015):
    they differ in the camera's x direction and in rotate axes; "eth2023" is "eth" with the analytic sphere's u
    turned half a revolution (ETH's course files up to 2023). None reads $CLRENDER_NORI_DIALECT."""
    from .loader import load_scene as _load

    return _load(path, nori_dialect=nori_dialect, **defines)


def render(scene, spp=None, seed=0, device=None, time_limit=None, progress=False, cluster=None, target_error=None,
           min_spp=None, max_spp=None, driver="auto", reconstruction="auto", **cluster_options):
    """Render a loaded scene on an OpenCL device and return its Film.

    ``driver``: "megakernel", "wavefront" (the path integrators) or "auto" (clrender/executors.py).
    ``reconstruction``: the film's, "splat" (Mitsuba's and Nori's: each sample weighted into every pixel within
    the filter's radius), "sampling" (filter importance sampling) or "auto" (splat where it can run: the
    megakernel, a filter wider than a box, no feature AOVs); the same expected image, see Renderer.
    With ``target_error=E`` the render is adaptive (clrender/adaptive.py): rounds over the pixels whose relative error
    is still above E, from ``min_spp`` (16) up to ``max_spp`` (default: ``spp``, else the scene's sample count)
    samples per pixel; ``film.count`` says where the samples went. One process only (not with ``cluster=``).

    With ``cluster=`` (a ``distributed.Client``, ``"local[:N]"``, ``"tcp://HOST:PORT"`` or a scheduler file)
    the samples are rendered by Dask workers; ``scene`` may then also be the XML path, and
    ``cluster_options`` are those of :func:`clrender.cluster.render` (files=, defines=, tasks=, ...)."""
    if target_error is not None:
        if cluster is not None:
            raise ValueError("adaptive sampling (target_error=) runs in one process, not on a cluster")
        from .renderer import Renderer

        return Renderer(scene, device=device, driver=driver, reconstruction=reconstruction).render_adaptive(
            target_error, min_spp, spp if max_spp is None else max_spp, seed=seed, time_limit=time_limit,
            progress=progress)
    if min_spp is not None or max_spp is not None:
        raise TypeError("min_spp and max_spp are options of adaptive renders (pass target_error=)")
    if cluster is not None:
        from .cluster import render as _cluster_render

        return _cluster_render(scene, spp=spp, seed=seed, cluster=cluster, device=device,
                               time_limit=time_limit, progress=progress, driver=driver,
                               reconstruction=reconstruction, **cluster_options)
    if cluster_options:
        raise TypeError(f"{', '.join(cluster_options)}: options of cluster renders only (pass cluster=)")
    from .renderer import render as _render

    return _render(scene, spp=spp, seed=seed, device=device, time_limit=time_limit, progress=progress,
                   driver=driver, reconstruction=reconstruction)


__all__ = ["load_scene", "render", "__version__"]
