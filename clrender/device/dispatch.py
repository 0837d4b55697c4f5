"""Kernel plugins: the registry, not hand-written switches, decides how the kernels reach a plugin.

A plugin class that runs on the device declares, beside its XML form::

    @register("bsdf", "roughconductor")
    class RoughConductor(Bsdf):
        kernel = "bsdfs/roughconductor.h"   # its OpenCL half; functions are named <prefix>_<method>
        PARAMS = [("eta", "float4"), ("k", "float4"), ("alpha", "float")]   # its row's parameter struct
        FLAGS = ("GLOSSY",)                 # capabilities the kernels test (never the type)
        METHODS = ("eval", "pdf", "sample") # which of the kind's methods its header defines

From the plugins registered in clrender.scene.registry (as it stands: this module imports no plugin; whoever
assembles the application imports clrender.plugins) this module derives, per kind:
- the tags: plugins numbered in the order of their prefixes (the kernel file's stem by default), so a tag never
  depends on import order, and no tag silently means a default plugin;
- the members of the row's union: each plugin's parameter struct (``b->p.microfacet.alpha`` in C,
  ``row["microfacet"]["alpha"]`` in numpy), laid out in the kind's row of clrender/device/layout.py ROWS;
- its methods and flag bits, from which clrender/device/codegen.py writes ``gen/<kind>_dispatch.h``: the plugin
  headers' includes and one ``switch`` per method.

Each plugin's include and cases are guarded by ``CLR_USE_<KIND>_<PREFIX>`` (or ``CLR_USE_ALL_PLUGINS``), and the
composite levels by ``<KIND>_COMPOSITE_LEVELS``: a render program gets the defines of the plugins its packed
scene uses (PluginSet, filled by pack_scene), so it compiles only their code. Tags never depend on the set: the
same tables run on a specialised and on a full program, and a tag outside the set takes the method's default
body. A build that defines no ``CLR_PLUGIN_SET`` (unit-test kernels, tools) holds every plugin.
Compare pbrt-v4's TaggedPointer::Dispatch and Mitsuba 3's BSDFFlags/EmitterFlags.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..scene import registry


@dataclass(frozen=True)
class Method:
    name: str
    ret: str
    params: str        # the C parameter list, shared by the dispatcher and every plugin's function
    args: str          # the call's arguments
    default: str       # body for plugins without this method and for unknown tags
    required: bool = False


@dataclass(frozen=True)
class Kind:
    tag: str                   # registry tag, e.g. "bsdf"
    struct: str                # its row in layout.ROWS, e.g. "Bsdf" (header fields, then a union of the plugins')
    flags: tuple               # capability flag names, bit i = 1 << i, emitted as <STRUCT>_<FLAG>
    dispatch_name: str         # generated functions are <dispatch_name>_<method>
    row: str                   # how the dispatcher's row pointer is named in `params`
    methods: tuple
    after: tuple = ()          # headers the generated file includes before the plugins'
    dispatched: bool = True    # False: no switch (integrators: one per program, chosen by -DINTEGRATOR)
    type_field: str = "type"   # the row's tag field the switch reads
    composite_levels: int = 0  # nesting levels of composite plugins (COMPOSITE = True) the generated code supports
    registry_tags: tuple = ()  # the object tags its plugins register under, per format (default: (tag,))
    use_name: str = ""         # the kind's word in CLR_USE_<KIND>_<PREFIX> (default: tag in capitals)

    @property
    def tags(self) -> tuple:
        return self.registry_tags or (self.tag,)

    @property
    def levels_define(self) -> str:
        """The define that says how many composite levels a specialised program compiles (0..composite_levels)."""
        return f"{self.use_name or self.tag.upper()}_COMPOSITE_LEVELS"


BSDF = Kind(
    tag="bsdf", struct="Bsdf",
    # UV: a parameter reads a texture that varies over the surface (set at packing; intersection computes uv).
    # TRANSMISSION: light may leave on the other side (a pass-through included, Mitsuba's Transmission); per row where
    # a parameter decides it (Bsdf.capabilities)
    flags=("DELTA", "DIFFUSE", "GLOSSY", "UV", "TRANSMISSION"), dispatch_name="bsdf", row="b",
    methods=(
        Method("eval", "vec3", "__global const Bsdf* b, const BsdfQuery* q", "b, q", "return v3s(0.0f);"),
        Method("pdf", "float", "__global const Bsdf* b, const BsdfQuery* q", "b, q", "return 0.0f;"),
        Method("sample", "vec3", "__global const Bsdf* b, BsdfQuery* q, float2 u", "b, q, u",
               "q->wo = v3(0.0f, 0.0f, 1.0f); q->eta = 1.0f; q->measure = MEASURE_SOLID_ANGLE; "
               "return v3s(0.0f);", required=True),
        Method("albedo", "vec3", "__global const Bsdf* b, const BsdfQuery* q", "b, q", "return v3s(1.0f);"),
        # the normal the BSDF shades with, in the local frame: a normalmap's or bumpmap's, (0, 0, 1) for the rest
        # (Mitsuba's BSDF::sh_frame, which aov's sh_normal shows)
        Method("normal", "vec3", "__global const Bsdf* b, const BsdfQuery* q", "b, q",
               "return v3(0.0f, 0.0f, 1.0f);"),
        # the fraction of light that goes straight through (Mitsuba's eval_null_transmission: 1 for null, 1 - opacity
        # for a mask): what volpath's shadow rays carry across the surface; 0 (the default) blocks them
        Method("null_transmission", "vec3", "__global const Bsdf* b, const BsdfQuery* q", "b, q",
               "return v3s(0.0f);"),
    ),
    after=("bsdfs/common.h", "texture.h"),
    # twosided(blendbsdf(mask(diffuse))) is three levels: each level is a switch over the composites that calls
    # the level below for their children (OpenCL C has no recursion), level 0 the leaf plugins.
    composite_levels=3)

# Textures: rows of their own table (SCENE_TABLES "textures"); a BSDF colour parameter declared as "texture" is a
# constant colour plus the index of a texture row (NONE: the constant), read through texture.h's param_color.
TEXTURE = Kind(
    tag="texture", struct="Texture", flags=(), dispatch_name="texture", row="t",
    methods=(Method("eval", "vec3", "__global const Texture* t, float2 uv", "t, uv", "return v3s(0.0f);",
                    required=True),),
    after=("math.h",))

EMITTER = Kind(
    tag="emitter", struct="Emitter", flags=("DELTA", "INFINITE", "SURFACE"), dispatch_name="emitter_row", row="em",
    methods=(
        Method("sample", "vec3", "const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u",
               "sd, em, q, u", "q->pdf = 0.0f; q->dist = 0.0f; return v3s(0.0f);", required=True),
        Method("pdf", "float", "const SceneData* sd, __global const Emitter* em, const EmitterQuery* q",
               "sd, em, q", "return 0.0f;"),
        Method("eval", "vec3", "const SceneData* sd, __global const Emitter* em, const EmitterQuery* q",
               "sd, em, q", "return v3s(0.0f);"),
    ),
    after=("emitters/common.h",))

# Shapes: each packs its own geometry into the scene's tables (clrender/shapes/<name>.py) and gives, in
# kernels/shapes/<prefix>.h, the surface at a BVH hit (used by scene_intersect) and the sampling of a point on it
# with its solid-angle density (used by the area emitter). Nori files call them <mesh>, Mitsuba files <shape>.
SHAPE = Kind(
    tag="mesh", struct="Shape", registry_tags=("mesh", "shape"), use_name="SHAPE",
    # per shape, set at packing (not capabilities of the plugin): HAS_NORMALS / HAS_UVS: per-vertex data present;
    # NEEDS_UV: its BSDF reads a texture over the surface or is anisotropic (analytic shapes compute uv only then;
    # the shading frame then follows dp/du, as Mitsuba's); FLIP_NORMALS:
    # analytic shapes turned inside out (meshes flip their winding and normals at loading instead)
    flags=("HAS_NORMALS", "HAS_UVS", "NEEDS_UV", "FLIP_NORMALS"), dispatch_name="shape", row="s",
    methods=(
        Method("surface", "bool",
               "const SceneData* sd, __global const Shape* s, const Ray* r, const Hit* h, Intersection* its",
               "sd, s, r, h, its", "return false;", required=True),
        Method("sample", "float", "const SceneData* sd, __global const Shape* s, vec3 ref, float2 u, "
               "ShapeSample* ss", "sd, s, ref, u, ss", "return 0.0f;", required=True),
        Method("pdf", "float", "const SceneData* sd, __global const Shape* s, vec3 ref, vec3 p, vec3 ng, "
               "vec3 wi", "sd, s, ref, p, ng, wi", "return 0.0f;", required=True),
    ),
    after=("shapes/common.h",))

# Integrators: their parameters share SceneInfo's union `p` (sd->info->p.av.length); the program includes the one
# integrator it runs (kernels/integrators/<kernel>.h), so there is nothing to dispatch.
INTEGRATOR = Kind(tag="integrator", struct="SceneInfo", flags=(), dispatch_name="integrator", row="info", methods=(),
                  dispatched=False)

# Reconstruction filters: their parameters are a union in the Camera row; the kernels evaluate the profile f(x)
# (|x| <= radius) through filter_profile_eval (kernels/filter.h's sampling weights).
RFILTER = Kind(
    tag="rfilter", struct="Camera", flags=(), dispatch_name="filter_profile", row="cam", type_field="filter_type",
    methods=(Method("eval", "float", "__global const Camera* cam, float x", "cam, x", "return 0.0f;",
                    required=True),),
    after=("math.h",))

# Phase functions: rows of the `phases` table that media point at (Medium.phase). wi points back along the path (to
# where the light goes), wo toward where it comes from, both in world space (kernels/phase/common.h).
PHASE = Kind(
    tag="phase", struct="Phase", flags=(), dispatch_name="phase", row="ph",
    methods=(
        Method("eval", "float", "__global const Phase* ph, const PhaseQuery* q", "ph, q", "return 0.0f;",
               required=True),
        # sets q->wo and q->pdf; returns the weight eval / pdf
        Method("sample", "float", "__global const Phase* ph, PhaseQuery* q, float2 u", "ph, q, u",
               "q->pdf = 0.0f; return 0.0f;", required=True),
    ),
    after=("phase/common.h",))

# Participating media: rows of the `media` table that shapes (interior, exterior) and the camera point at.
# HOMOGENEOUS: sigma_t is the same everywhere (free flights are sampled in closed form, kernels/integrators/media.h;
# the others by delta tracking against their majorant); SAMPLE_EMITTERS: scattering vertices sample lights
# (Mitsuba's sample_emitters); SPECTRAL_EXTINCTION: sigma_t may differ between the channels (Mitsuba's
# has_spectral_extinction; the estimator here is the same either way).
MEDIUM = Kind(
    tag="medium", struct="Medium", flags=("HOMOGENEOUS", "SAMPLE_EMITTERS", "SPECTRAL_EXTINCTION"),
    dispatch_name="medium", row="m",
    methods=(
        Method("sigma_t", "vec3", "const SceneData* sd, __global const Medium* m, vec3 p", "sd, m, p",
               "return v3s(0.0f);", required=True),
        Method("albedo", "vec3", "const SceneData* sd, __global const Medium* m, vec3 p", "sd, m, p",
               "return v3s(0.0f);", required=True),
        # a bound on every channel of sigma_t inside the medium's extent (heterogeneous media: the null-collision
        # methods' majorant)
        Method("majorant", "float", "const SceneData* sd, __global const Medium* m", "sd, m", "return 0.0f;"),
        # narrows [*t0, *t1] along o + t d to where the medium can have extinction (Mitsuba's intersect_aabb);
        # false if nothing of it is left
        Method("clip", "bool", "const SceneData* sd, __global const Medium* m, vec3 o, vec3 d, float* t0, "
               "float* t1", "sd, m, o, d, t0, t1", "return true;"),
    ),
    after=("math.h",))

# Volumes: rows of the `volumes` table that heterogeneous media read sigma_t and albedo from (a grid's voxels are in
# `grid_data`); eval is the value at a world-space point, a colour (a one-channel volume's value in all three).
VOLUME = Kind(
    tag="volume", struct="Volume", flags=(), dispatch_name="volume", row="v",
    methods=(Method("eval", "vec3", "const SceneData* sd, __global const Volume* v, vec3 p", "sd, v, p",
                    "return v3s(0.0f);", required=True),),
    after=("math.h",))

KINDS = {k.tag: k for k in (TEXTURE, SHAPE, BSDF, EMITTER, INTEGRATOR, RFILTER, PHASE, MEDIUM, VOLUME)}


def prefix_of(cls) -> str:
    return getattr(cls, "prefix", None) or Path(cls.kernel).stem.split(".")[0]


def plugins(kind: str) -> list[type]:
    """The registered device plugins of `kind` in every scene format, in tag order (sorted by prefix). Classes
    that share a prefix (a Mitsuba-format subclass of a Nori plugin, say) share its kernel, tag and row: the first
    in (format, type name) order stands for them, and they must agree on PARAMS and FLAGS."""
    found = {}
    for cls in _classes(KINDS[kind]):
        if not getattr(cls, "kernel", None):
            continue
        first = found.setdefault(prefix_of(cls), cls)
        if first is not cls and (cls.kernel != first.kernel or
                                 list(getattr(cls, "PARAMS", ())) != list(getattr(first, "PARAMS", ()))):
            raise RuntimeError(f"{cls.__qualname__} and {first.__qualname__} share the kernel prefix "
                               f"{prefix_of(cls)!r} but not their kernel file or PARAMS")
    return [found[p] for p in sorted(found)]


# Words a union member cannot be called in OpenCL C (address spaces, types, C keywords).
_C_RESERVED = set("""auto bool break case char const constant continue default do double else enum extern float for
global goto half if image1d_t image2d_t image3d_t inline int kernel local long private read_only read_write
register restrict return sampler_t short signed sizeof static struct switch typedef uint ulong union unsigned
ushort uchar void volatile while write_only""".split())


def member_of(cls) -> str:
    """The plugin's member of its row's union (`b->p.<member>` in C, `row[<member>]` in numpy): its prefix, with
    a trailing underscore where that is a reserved word (the `constant` emitter's is `constant_`)."""
    p = prefix_of(cls)
    return p + "_" if p in _C_RESERVED or p.startswith("__") else p


def signature() -> tuple:
    """Everything the generated C depends on (a cache key that changes when a plugin is (un)registered)."""
    out = []
    for kind in KINDS.values():
        for cls in plugins(kind.tag):
            out.append((kind.tag, prefix_of(cls), cls.kernel, tuple(tuple(f) for f in getattr(cls, "PARAMS", ())),
                        tuple(getattr(cls, "FLAGS", ())), tuple(methods_of(cls, kind)), is_composite(cls)))
    return tuple(out)


def methods_of(cls, kind: Kind) -> list[str]:
    if not kind.methods:
        return []
    declared = list(getattr(cls, "METHODS", [m.name for m in kind.methods]))
    known = {m.name for m in kind.methods}
    unknown = [m for m in declared if m not in known]
    if unknown:
        raise RuntimeError(f"{cls.__qualname__} declares unknown {kind.tag} methods {unknown}; "
                           f"known: {sorted(known)}")
    missing = [m.name for m in kind.methods if m.required and m.name not in declared]
    if missing:
        raise RuntimeError(f"{cls.__qualname__} must implement {missing}")
    return declared


def tag_of(cls) -> int:
    """The type tag the kernels switch on (the plugin's position among its kind's prefixes)."""
    kind = KINDS[_kind_tag(cls)]
    return [prefix_of(c) for c in plugins(kind.tag)].index(prefix_of(cls))


def flags_of(cls, names=None) -> int:
    """The flag bits of `names` (default: the class's FLAGS) in the row of plugin class `cls`."""
    kind = KINDS[_kind_tag(cls)]
    bits = 0
    for f in cls.FLAGS if names is None else names:
        if f not in kind.flags:
            raise RuntimeError(f"{cls.__qualname__}: unknown {kind.tag} flag {f!r}; known: {kind.flags}")
        bits |= 1 << kind.flags.index(f)
    return bits


def _classes(kind: Kind) -> list[type]:
    out = []
    for t in kind.tags:
        out += [c for c in registry.registered_classes(t) if c not in out]
    return out


def _kind_tag(cls) -> str:
    for tag, kind in KINDS.items():
        if getattr(cls, "kernel", None) and cls in _classes(kind):
            plugins(tag)    # checks that classes sharing its prefix agree
            return tag
    raise RuntimeError(f"{cls.__qualname__} is not a registered device plugin (it needs @register and `kernel`)")


def params_struct(cls) -> str:
    return "".join(w.capitalize() for w in prefix_of(cls).split("_")) + "Params"


def flag_defines() -> dict[str, int]:
    return {f"{k.struct.upper()}_{f}": 1 << i for k in KINDS.values() for i, f in enumerate(k.flags)}


def is_composite(cls) -> bool:
    """A composite plugin (twosided, blendbsdf, mask) holds other rows of its table and calls their methods."""
    return bool(getattr(cls, "COMPOSITE", False))


ALL_PLUGINS = "CLR_USE_ALL_PLUGINS"   # defined (or no CLR_PLUGIN_SET): every registered plugin is compiled
PLUGIN_SET = "CLR_PLUGIN_SET"         # defined by a specialised build, with one CLR_USE_* per plugin it uses


def use_define(kind: Kind, prefix: str) -> str:
    """The define that puts plugin `prefix` of `kind` into a specialised program (CLR_USE_BSDF_DIFFUSE)."""
    return f"CLR_USE_{kind.use_name or kind.tag.upper()}_{prefix.upper()}"


@dataclass(frozen=True)
class PluginSet:
    """The device plugins a packed scene uses: (kind tag, prefix) pairs, and the composite nesting depth of each
    kind that has composites (0: no composite). ``defines()`` are the -D options of a program built for it."""
    used: frozenset
    levels: tuple = ()     # ((kind tag, depth), ...)

    @classmethod
    def from_tags(cls, tags: dict, levels: dict | None = None) -> "PluginSet":
        """From the type tags found in packed rows, per kind tag ({"bsdf": {3, 6}, ...})."""
        used = set()
        for kind_tag, found in tags.items():
            classes = plugins(kind_tag)
            for t in found:
                t = int(t)
                if not 0 <= t < len(classes):
                    raise ValueError(f"{kind_tag} tag {t} is not a registered plugin (0..{len(classes) - 1})")
                used.add((kind_tag, prefix_of(classes[t])))
        return cls(frozenset(used), tuple(sorted((levels or {}).items())))

    def defines(self) -> dict:
        out = {PLUGIN_SET: None}
        for kind_tag, prefix in sorted(self.used):
            out[use_define(KINDS[kind_tag], prefix)] = None
        for kind_tag, depth in self.levels:
            kind = KINDS[kind_tag]
            if not 0 <= depth <= kind.composite_levels:
                raise ValueError(f"{kind_tag} composites nested {depth} deep; at most {kind.composite_levels}")
            out[kind.levels_define] = int(depth)
        return out
