"""Reading Mitsuba 0.x / 1.x files (a root ``<scene version="0.5.0">``, say) as Mitsuba 3.9.1 reads them, and a
little further where an old file's meaning is clear and Mitsuba 3 refuses it.

Mitsuba 3 upgrades every object of a file older than 2.0 while parsing (``upgrade_from_v1`` in its
``src/core/parser.cpp``): each parameter name (a property's or a nested object's ``name``) goes from camelCase to
snake_case (:func:`camel_to_snake`, its rule exactly: ``toWorld`` -> ``to_world``, ``intIOR`` -> ``int_ior``);
then ``diffuse``'s ``diffuse_reflectance`` becomes ``reflectance``; and any object's ``uoffset``/``voffset``/
``uscale``/``vscale`` become one ``to_uv`` transform, scale(uscale, vscale) * translate(uoffset, voffset).
:func:`upgrade` does the same to a :class:`PluginSpec` of such a file.

Beyond Mitsuba 3 (each with a log line or a located error):

- parameters of Mitsuba 0.6 that no longer mean anything to a renderer of surfaces in RGB
  (:data:`DROPPED`, e.g. ``strictNormals``, ``highQualityEdges``) are ignored with a warning, where
  Mitsuba 3 stops on an unused parameter;
- ``<lookAt>`` is read as ``<lookat>``, and ``<srgb>`` as the ``<rgb>`` of its linear values (mitsuba_xml.py);
- the ``ldrfilm``, the ``sobol``/``halton``/``hammersley`` samplers (with their ``scramble``) and meshes' ``maxSmoothAngle`` are plugins'
  own parameters (films/ldrfilm.py, samplers/independent.py, shapes/trianglemesh.py);
- an old bitmap's MIP-mapped filterType, per-axis wrap modes and gamma, where they mean something we have;
- an old homogeneous medium's ``sigmaA``/``sigmaS`` (absorption and scattering) as Mitsuba 3's ``sigma_t``/``albedo``;
- an old heterogeneous medium's ``density`` volume as Mitsuba 3's ``sigma_t`` (0.6: sigma_t = scale density), its
  ``method`` and ``stepSize`` (delta tracking or ray marching of the same medium) ignored with a log line, and an old
  ``gridvolume`` spanning the bounding box its file gives (0.6 had no unit cube: ``use_grid_bbox`` true);
- a shape that bounds a medium and has no BSDF is an index-matched boundary (a ``null`` BSDF), as Mitsuba 0.6 made
  it (its Shape::configure), where Mitsuba 3.9.1 gives every shape without one a diffuse BSDF, which turns an old
  file's medium into an opaque grey ball (lajolla's volpath tests 3-6, its hetvol scenes);
- the wrappers ``adaptive`` and ``irrcache`` render as the integrator they hold (:data:`WRAPPERS`);
- an integrator that clrender does not have (:data:`INTEGRATORS`) is a located error that names what it has.
"""
from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from ..errors import SceneError
from .spec import PluginSpec, PropertyList
from .transform import Transform

log = logging.getLogger("clrender")

#: Mitsuba 0.6 parameters that have no counterpart in Mitsuba 3 or here, by object tag; they are ignored with a
#: warning (their snake_case names, as the upgrade makes them)
DROPPED = {
    "integrator": ("strict_normals",),            # the path tracers' light-leak guard at shading normals
    "film": ("attach_log", "high_quality_edges"),  # a log in the file, edge pixels filtered from outside the film
    "sampler": ("dimension",),                    # ldsampler's and stratified's count of dimensions
    "texture": ("max_anisotropy", "cache"),       # bitmap's EWA filter width and its MIP-map cache file
    "shape": ("collapse",),                       # obj's merging of its groups into one mesh: the same surface
}

#: Mitsuba 0.6 integrators that clrender does not have, with what they do (a path tracer renders the same image
#: for each of them but the approximate ones, only with other noise); 0.6's `ptracer` is not one: Mitsuba 3.9.1
#: reads it as its own ptracer (maxDepth, rrDepth upgraded), and so does clrender (integrators/path.py)
INTEGRATORS = {
    "bdpt": "bidirectional path tracing", "pssmlt": "primary sample space MLT", "mlt": "Metropolis light transport",
    "erpt": "energy redistribution path tracing", "photonmapper": "photon mapping",
    "ppm": "progressive photon mapping", "sppm": "stochastic progressive photon mapping",
    "vpl": "virtual point lights", "multichannel": "several integrators into one image",
    "field": "a field of the first hit", "volpath_simple": "simple volumetric path tracing",
}


#: Mitsuba 0.6 integrators that wrap another and change only how it is sampled (adaptive: samples per pixel until
#: an error bound; irrcache: caches the nested one's indirect light, an approximation): rendered as the nested one
WRAPPERS = {"adaptive": "adaptive sampling", "irrcache": "irradiance caching"}


def unwrap(spec, location):
    """The integrator nested in a wrapper (a located error without exactly one), its own parameters ignored."""
    inner = [c for c in spec.children if c.tag == "integrator"]
    if len(inner) != 1 or len(spec.children) != 1:
        raise SceneError(f"<integrator type=\"{spec.type}\"> ({WRAPPERS[spec.type]}) must hold one nested "
                         f"<integrator>, which clrender renders with", location)
    log.warning("%s: <integrator type=\"%s\"> (%s, Mitsuba 0.x) is rendered as the integrator it wraps, <integrator "
                "type=\"%s\">; its own parameters (%s) are ignored", location, spec.type, WRAPPERS[spec.type],
                inner[0].type, ", ".join(spec.props.names()) or "none")
    return inner[0]


def camel_to_snake(name: str) -> str:
    """Mitsuba 3.9.1's camel_to_underscore_case: before an upper-case letter that follows a lower-case one, an
    underscore, and that letter and the upper-case ones right after it in lower case (``intIOR`` -> ``int_ior``,
    ``cropOffsetX`` -> ``crop_offset_x``); everything else as written."""
    out = []
    i = 0
    while i < len(name):
        c = name[i]
        if i > 0 and name[i - 1].islower() and c.isupper():
            out.append("_" + c.lower())
            while i + 1 < len(name) and name[i + 1].isupper():
                i += 1
                out.append(name[i].lower())
        else:
            out.append(c)
        i += 1
    return "".join(out)


def _set(props, name: str, tag: str, value) -> None:
    where = props.location(name)
    props.remove(name)
    props.add(name, tag, value, where)


def _upgrade_bitmap(props) -> None:
    """An old bitmap's settings whose meaning carries over: MIP-mapped filters (Mitsuba 3, and we, filter
    bilinearly: the same at magnification, sharper where a texel is smaller than a pixel), one wrap mode per axis
    (the same for both, as Mitsuba 3 and we have one), and ``gamma`` 1 (raw data) or -1 (sRGB) as ``raw``."""
    if props.has("filter_type") and props.tag("filter_type") == "string":
        value = props.get_string("filter_type")
        if value in ("trilinear", "ewa"):
            log.warning("%s: filterType '%s' (MIP-mapped) of a Mitsuba 0.x bitmap: clrender filters bilinearly, as "
                        "Mitsuba 3 does", props.location("filter_type"), value)
            _set(props, "filter_type", "string", "bilinear")
    axes = [n for n in ("wrap_mode_u", "wrap_mode_v") if props.has(n)]
    if axes:
        modes = {props.get_string(n) for n in axes}
        if len(modes) > 1 or props.has("wrap_mode"):
            raise SceneError("wrap_mode_u and wrap_mode_v differ (or wrap_mode is given too); clrender, as Mitsuba 3, "
                             "takes one wrap_mode for both axes", props.location(axes[0]))
        where = props.location(axes[0])
        for n in axes:
            props.remove(n)
        props.add("wrap_mode", "string", modes.pop(), where)
    if props.has("gamma") and not props.has("raw"):
        gamma = props.get_float("gamma")
        if gamma not in (1.0, -1.0):
            raise SceneError(f"a bitmap's gamma {gamma:g}: clrender reads images as sRGB (gamma -1) or as raw data "
                             f"(gamma 1), as Mitsuba 3's 'raw' parameter does", props.location("gamma"))
        where = props.location("gamma")
        props.remove("gamma")
        props.add("raw", "boolean", gamma == 1.0, where)


def _upgrade_homogeneous(props) -> None:
    """Mitsuba 0.x's homogeneous medium given by its absorption and scattering coefficients ``sigmaA``, ``sigmaS``
    (0.6's other form, ``sigmaT``/``albedo``, is Mitsuba 3's): the same medium as Mitsuba 3's ``sigma_t`` = sigma_a +
    sigma_s and ``albedo`` = sigma_s / sigma_t (0 where nothing is there); 0.6's ``scale`` multiplied both, as 3's
    multiplies sigma_t. Mitsuba 3.9.1 refuses the old names as unreferenced (lajolla's volpath tests use them)."""
    given = [n for n in ("sigma_a", "sigma_s") if props.has(n)]
    if not given:
        return
    where = props.location(given[0])
    if len(given) == 1:
        other = "sigma_s" if given[0] == "sigma_a" else "sigma_a"
        raise SceneError(f"an old homogeneous medium's {given[0]} needs {other} beside it (clrender does not have "
                         f"Mitsuba 0.x's material presets that filled it in)", where)
    for n in ("sigma_t", "albedo", "material"):
        if props.has(n):
            raise SceneError(f"'{n}' given together with sigma_a and sigma_s; give one form of the medium "
                             f"(sigma_a/sigma_s, or sigma_t/albedo)", props.location(n))
    sigma_a, sigma_s = (props.get_color(n, unbounded=True) for n in given)
    for n, v in (("sigma_a", sigma_a), ("sigma_s", sigma_s)):
        if np.any(v < 0):
            raise SceneError(f"{n} must be non-negative, got {v.tolist()}", props.location(n))
    sigma_t = sigma_a + sigma_s
    albedo = np.divide(sigma_s, sigma_t, out=np.zeros(3), where=sigma_t > 0)
    for n in given:
        props.remove(n)
    props.add("sigma_t", "rgb", sigma_t, where)
    props.add("albedo", "rgb", albedo, where)


def _upgrade_heterogeneous(spec, shared: set[int]) -> None:
    """Mitsuba 0.6's heterogeneous medium: its ``density`` volume is the extinction (times ``scale``, as Mitsuba 3's
    ``sigma_t``); ``method`` (woodcock: delta tracking; simpson: ray marching) and ``step_size`` choose how the same
    medium is sampled, which clrender's tracking does without them; ``orientation`` (the micro-flake model's fibre
    directions) clrender does not have."""
    props = spec.props
    for i, child in enumerate(spec.children):
        if child.name == "density":
            if any(c.name == "sigma_t" for c in spec.children) or props.has("sigma_t"):
                raise SceneError("an old heterogeneous medium's density is its sigma_t, which is given too",
                                 child.location)
            if i in shared:
                spec.children[i] = replace(child, name="sigma_t")
            else:
                child.name = "sigma_t"
        elif child.name == "orientation":
            raise SceneError("an old heterogeneous medium's orientation volume belongs to the micro-flake phase "
                             "function, which clrender does not have (isotropic and hg)", child.location)
    for name in ("method", "step_size"):
        if props.has(name):
            props.mark_used(name)
            log.info("%s: '%s' of the Mitsuba 0.x heterogeneous medium picks how it is sampled; clrender tracks "
                     "the same medium without it", props.location(name), name)


def srgb_to_linear(value) -> np.ndarray:
    """Mitsuba 0.x's ``<srgb>``: an sRGB-encoded colour, ``#rrggbb`` or 1 or 3 numbers in [0, 1], as linear RGB.
    A string that is not ``#rrggbb`` raises ValueError (the caller then reads it as numbers)."""
    if isinstance(value, str):
        text = value.strip()
        if not (text.startswith("#") and len(text) == 7):
            raise ValueError(text)
        x = np.array([int(text[i:i + 2], 16) for i in (1, 3, 5)]) / 255.0
    else:
        x = np.repeat(value, 3) if np.size(value) == 1 else np.asarray(value, np.float64)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def check_integrator(type_name: str, location, known: list[str]) -> None:
    """A located error for an old integrator that clrender does not have."""
    what = INTEGRATORS.get(type_name)
    if what is not None:
        raise SceneError(f"the Mitsuba 0.x integrator '{type_name}' ({what}) is not available in clrender (nor in "
                         f"Mitsuba 3); clrender's Mitsuba integrators: {', '.join(known)}; 'path' converges to "
                         f"the same image as the unbiased ones", location)


def upgrade(spec, shared: set[int]) -> None:
    """Mitsuba's upgrade of one object read from a file older than 2.0, after its names went to snake_case.
    ``shared``: the indices of children that a ``<ref>`` put there (the referenced object is not changed in place).
    """
    props = spec.props
    if spec.type == "diffuse":
        if props.has("diffuse_reflectance"):
            props.rename("diffuse_reflectance", "reflectance")
        for i, child in enumerate(spec.children):
            if child.name == "diffuse_reflectance":
                if i in shared:
                    spec.children[i] = replace(child, name="reflectance")
                else:
                    child.name = "reflectance"
    uv = [n for n in ("uoffset", "voffset", "uscale", "vscale") if props.has(n)]
    if uv:
        where = props.location(uv[0])
        v = {n: props.get_float(n) for n in uv}
        for n in uv:
            props.remove(n)
        try:
            to_uv = (Transform.scale([v.get("uscale", 1.0), v.get("vscale", 1.0), 1.0])
                     @ Transform.translate([v.get("uoffset", 0.0), v.get("voffset", 0.0), 0.0]))
        except ValueError as e:
            raise SceneError(f"uscale/vscale: {e}", where) from None
        if props.has("to_uv"):
            raise SceneError("to_uv given together with uoffset/voffset/uscale/vscale, which Mitsuba turns into a "
                             "to_uv; give one of them", where)
        props.add("to_uv", "transform", to_uv, where)
    if spec.tag == "texture" and spec.type == "bitmap":
        _upgrade_bitmap(props)
    if spec.tag == "medium" and spec.type == "homogeneous":
        _upgrade_homogeneous(props)
    if spec.tag == "medium" and spec.type == "heterogeneous":
        _upgrade_heterogeneous(spec, shared)
    if spec.tag == "volume" and spec.type == "gridvolume" and not props.has("use_grid_bbox"):
        props.add("use_grid_bbox", "boolean", True, spec.location)
    if spec.tag == "shape" and not any(c.tag in ("bsdf", "emitter") for c in spec.children) and \
            any(c.tag == "medium" and c.name in ("interior", "exterior") for c in spec.children):
        spec.children.append(PluginSpec("bsdf", "null", None, PropertyList(), location=spec.location,
                                        dialect=spec.dialect, format=spec.format))
    for name in DROPPED.get(spec.tag, ()):
        if props.has(name):
            props.mark_used(name)
            log.warning("%s: '%s' of the Mitsuba 0.x %s has no counterpart in Mitsuba 3 or clrender; ignored",
                        props.location(name), name, spec.describe())
