"""The one source of truth for every struct shared by the host and the kernels.

Each struct is declared once here as a list of (field, C type[, count]): the plain ones in ``STRUCTS``, the rows
of the scene's plugin tables in ``ROWS`` (their header fields, then a fixed-size union ``p`` of the registered
plugins' parameter structs, which clrender/device/dispatch.py lists). From that we derive the numpy dtype (explicit
offsets, C alignment: a float4/uint4 is 16-byte aligned) used to pack tables on the host; clrender/device/codegen.py
writes the C ``typedef struct`` text of the same fields that ``program.build_program`` prepends to every kernel
source. Only 4-byte scalars and 16-byte vectors are allowed: ``float3`` is 16 bytes on the device and 12 in numpy, so
it never appears in a buffer. ``tests/test_layout.py`` compiles a probe kernel and compares sizeof/offsetof.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..scene.registry import snapshot
from . import dispatch

_SCALARS = {"float": ("<f4", 4, 4), "uint": ("<u4", 4, 4), "int": ("<i4", 4, 4)}
_VECTORS = {"float4": ("<f4", 16, 16), "uint4": ("<u4", 16, 16)}

NONE = 0xFFFFFFFF  # "no index" in uint fields (no emitter, no texture, ...)

BSDF_TABLE_SIZE = 64  # entries of a BsdfTable (kernels: BSDF_TABLE_SIZE)

# Structs with no plugins behind them (the shape, BSDF, emitter, texture, integrator and camera rows are the ROWS
# below).
STRUCTS: dict[str, list[tuple]] = {
    # a BSDF's lookup table on BSDF_TABLE_SIZE uniform nodes (roughplastic's coating transmittance T(mu)); its row
    # holds the index, so a row stays the size of the other BSDFs' parameters
    "BsdfTable": [("values", "float", BSDF_TABLE_SIZE)],
}


@dataclass(frozen=True)
class Row:
    """A plugin table's row: the header fields, then the union `p` of its plugins' parameter structs, of a fixed
    size so rows keep one layout whatever is registered (a plugin's PARAMS must fit)."""
    header: tuple
    union_bytes: int


# Keyed by the struct name a dispatch.Kind names (Kind.struct).
ROWS: dict[str, Row] = {
    # Camera: the camera, then its reconstruction filter's parameters
    "Camera": Row(header=(
        ("to_world", "float4", 4),   # columns of the camera-to-world matrix: x axis, y axis, z axis, origin
        ("tan_half_fov", "float"),   # tan(fov/2), horizontal
        ("inv_aspect", "float"),     # height / width
        ("near_clip", "float"), ("far_clip", "float"),
        ("width", "uint"), ("height", "uint"),
        ("filter_type", "uint"),     # the filter's tag
        ("filter_bins", "uint"),     # size of the filter's 1-D sampling table
        ("filter_radius", "float"),
        # the image is the window (crop_x, crop_y, width, height) of a film_width x film_height film
        ("crop_x", "float"), ("crop_y", "float"), ("film_width", "float"), ("film_height", "float"),
        ("clip_window", "uint"),     # 1: samples whose filter offset leaves the window count with weight 0
        ("lens_radius", "float"),    # thin lens aperture radius (0: pinhole)
        ("focus_distance", "float"),  # distance of the plane in focus along the viewing axis
        ("ortho", "uint")),          # 1: orthographic (rays along the z axis from the film's plane)
        union_bytes=16),
    "Texture": Row(header=(("type", "uint"), ("pad", "uint", 3)), union_bytes=48),
    "Shape": Row(header=(
        ("type", "uint"), ("flags", "uint"),
        ("bsdf", "uint"),
        ("emitter", "uint"),     # NONE if the shape does not emit
        ("first", "uint"),       # emitting meshes: offset of their triangles' leaf references in the `tri_refs`
                                 # table (NONE when not emitting); spheres: row of the spheres table;
                                 # SDF grids: offset of their values in `grid_data`
        ("count", "uint"),       # meshes: triangle count; spheres: 1
        ("cdf", "uint"),         # emitting meshes: offset of their triangle-area CDF in the `cdf` table
        ("area", "float"),       # emitting shapes: total surface area
        ("interior", "uint"),    # the medium inside (a row of `media`; NONE: vacuum), Mitsuba's interior
        ("exterior", "uint")),   # the medium outside (on the side the normal points to)
        union_bytes=80),         # sdfgrid's map and resolution
    "Bsdf": Row(header=(("type", "uint"), ("flags", "uint"), ("pad", "uint", 2)), union_bytes=128),
    "Emitter": Row(header=(
        ("type", "uint"), ("flags", "uint"),
        ("shape", "uint"),        # surface emitters: the emitting shape (which samples its own surface)
        ("pad", "uint", 5)),
        union_bytes=96),
    # SceneInfo: scene-wide numbers, then the integrator's parameters (sd->info->p.av.length)
    "SceneInfo": Row(header=(
        ("n_prims", "uint"), ("n_tris", "uint"), ("n_spheres", "uint"), ("n_emitters", "uint"),
        ("bounds_center", "float4"),  # xyz: centre of the scene's bounding sphere, w: its radius
        ("max_depth", "uint"),        # path length limit (0xFFFFFFFF: none)
        ("rr_depth", "uint"),         # Russian roulette starts at this depth
        ("n_infinite", "uint"),       # entries of the infinite-emitter index table
        ("emitter_cdf", "uint"),      # NONE: choose a light uniformly; else its selection CDF's offset in `cdf`
        ("n_meshes", "uint"),         # rows of the mesh_vertices table
        ("n_media", "uint"),          # rows of the media table (0: the scene is a vacuum)
        ("camera_medium", "uint")),   # the medium the camera sits in (NONE: vacuum)
        union_bytes=32),
    # a participating medium (clrender/media/), with the row of its phase function in `phases`
    "Medium": Row(header=(("type", "uint"), ("flags", "uint"), ("phase", "uint"), ("pad", "uint")),
                  union_bytes=48),
    "Phase": Row(header=(("type", "uint"), ("pad", "uint", 3)), union_bytes=16),
    # a volume (clrender/volumes/) that a heterogeneous medium reads sigma_t or albedo from: its world-space bounding
    # box (Mitsuba's Volume::bbox, the box of to_world's image of the unit cube), which bounds the medium's extinction
    "Volume": Row(header=(("type", "uint"), ("pad", "uint", 3), ("bbox_min", "float4"), ("bbox_max", "float4")),
                  union_bytes=80),
}
# The scene's tables, in kernel-argument order: (name, element type, what it holds). The kernels' SceneData
# struct, its SCENE_ARGS argument list (each table is the argument s_<name>) and SCENE_INIT are generated from
# this list; clrender.pack.SceneBuffers holds one numpy array per entry, and the host sets them by name.
SCENE_TABLES: list[tuple[str, str, str]] = [
    ("nodes", "float4", "BVH nodes (2-, 4- or 8-wide layout, see BVH_WIDTH)"),
    ("prims", "float4", "primitives in BVH leaf order, 10 words each in blocks of up to 4 (triangles' vertices, "
                        "spheres), clrender/accel/primitives.py pack_leaf_blocks; the only copy of the vertices"),
    ("normals", "ushort", "per vertex, x y z as 16-bit signed fixed point over 32767 (meshes with "
                          "SHAPE_HAS_NORMALS; clrender/shapes/trianglemesh.py fixed_normals)"),
    ("uvs", "float2", "per vertex (meshes with SHAPE_HAS_UVS)"),
    ("tri_index", "uint", "per leaf-order position (Hit.prim >> PRIM_REF_POS_SHIFT): the triangle's three vertex "
                          "indices (NONE at a sphere's position)"),
    ("mesh_vertices", "uint2", "per mesh, in shape order: (its first vertex index, its shape); a triangle's shape is "
                               "the row of the last first vertex <= its i0"),
    ("tri_refs", "uint", "emitting meshes' triangles' leaf references (Hit.prim), in mesh order (Shape.first)"),
    ("spheres", "float4", "centre xyz, radius"),
    ("sphere_shape", "uint", "the shape of each sphere"),
    ("shapes", "Shape", "one row per shape"),
    ("bsdfs", "Bsdf", "one row per BSDF"),
    ("bsdf_tables", "BsdfTable", "BSDFs' lookup tables, each stored once (roughplastic's p.roughplastic.table)"),
    ("emitters", "Emitter", "one row per emitter"),
    ("cdf", "float", "emitting meshes' triangle-area CDFs, back to back (Shape.cdf)"),
    ("textures", "Texture", "one row per texture that a BSDF parameter refers to"),
    ("infinite", "uint", "indices of the infinite emitters (info->n_infinite of them)"),
    ("media", "Medium", "one row per participating medium (shapes' interior/exterior, the camera's)"),
    ("phases", "Phase", "the media's phase functions (Medium.phase)"),
    ("volumes", "Volume", "the volumes heterogeneous media read sigma_t and albedo from"),
    ("grid_data", "float", "gridvolumes' voxels and SDF grids' values, back to back: ((z yres + y) xres + x) "
                           "channels + c from each volume's offset (p.gridvolume.offset) or SDF grid's (Shape.first)"),
    ("info", "SceneInfo", "scene-wide numbers and the integrator's parameters"),
]

# The film's per-pixel accumulators: (argument, element type, what each pixel's element holds, when it exists). One
# buffer of one element per pixel each; the render kernels take them as FILM_ARGS (each the argument of its name),
# splat.cl's gather a splatting film's as SPLAT_FILM_ARGS; the host allocates, downloads and reads them by these names
# (clrender/renderer.py, film.py Film.sums), and the film's memory is counted from their sizes (memcheck.py).
# When: "always"; "count_rays": in builds with CLRENDER_COUNT_RAYS, else a one-element dummy the kernel never
# touches, so both builds take the same arguments; "splat": a splatting film's only (not a render kernel argument).
FILM_ACCUMULATORS: list[tuple[str, str, str, str]] = [
    ("acc0", "float4", "xyz: sum of w L, w: sum of w (the filter weights)", "always"),
    ("acc1", "float4", "xyz: sum of (w L)^2, w: samples accumulated", "always"),
    ("bad", "uint", "samples dropped for being NaN/Inf", "always"),
    ("rays", "uint4", "rays traced: camera, other closest-hit, shadow (any-hit), 0", "count_rays"),
    ("acc2", "float4", "xyz: sum of w^2 L, w: sum of w^2 (with acc1 the variance of a splatted pixel's ratio)",
     "splat"),
]
#: (argument, type) of the accumulators the render kernels take as FILM_ARGS, and splat.cl's gather as SPLAT_FILM_ARGS
FILM_ARGS = [(n, t) for n, t, _what, when in FILM_ACCUMULATORS if when != "splat"]
SPLAT_FILM_ARGS = [(n, t) for n, t, _what, when in FILM_ACCUMULATORS if when != "count_rays"]


# Type tags and flag bits, shared the same way (emitted as #defines).
ENUMS: dict[str, int] = {
    "BSDF_TABLE_SIZE": BSDF_TABLE_SIZE,
    # BVH encodings shared by the builders (clrender/accel) and the traversals (kernels/bvh*.h)
    "BVH_LEAF_BIT": 0x80000000,       # a node reference to a leaf
    "BVH_SPHERE_BIT": 0x80000000,     # a primitive id of an analytic sphere
    "BVH_SDF_BIT": 0x40000000,        # with BVH_SPHERE_BIT: a voxel of an SDF grid (the other bits: its shape)
    "BVH_STACK_SIZE": 64,             # 2-wide traversal stack (the builder keeps the depth below it)
    "BVH4_STACK_SIZE": 64,            # 4-wide traversal stack (the collapse checks the tree needs no more)
    "BVH8_STACK_SIZE": 96,            # 8-wide traversal stack (likewise)
    # float4 entries per splat in adaptive sampling's splatting store (kernels/splat.cl, executors.SplatExecutor)
    "SPLAT_STORE_ENTRIES": 3,
    "BVH4_COUNT_SHIFT": 27,           # 4-wide leaf reference: LEAF_BIT | (count - 1) << 27 | first
    "BVH4_MAX_LEAF_COUNT": 16,
    # A triangle's leaf reference, the id word of its lane in the primitive table (so Hit.prim): its leaf-order
    # position pos, its lane l in its block and the block's size c, as pos << 4 | l << 2 | (c - 1); the block
    # starts at pos - l, so the kernels find its vertices there (kernels/shapes/mesh.h mesh_triangle)
    "PRIM_REF_POS_SHIFT": 4,
    "PRIM_REF_MAX_POS": (1 << 27) - 1,
}


# Plugin parameters that may be a constant or a texture: (C type of the constant). Each is laid out as the constant
# `name` and the texture row's index `name_tex` (NONE: the constant), filled by clrender.textures.texture.param and
# read in C by kernels/texture.h's param_color / param_float.
TEXTURED = {"texture": "float4",          # a colour (xyz)
            "float_texture": "float"}     # a float (a texture's float view: Mitsuba's eval_1)


def expand(fields) -> list:
    """The fields as laid out: a TEXTURED parameter is its constant and the index of a texture row."""
    out = []
    for f in fields:
        if f[1] in TEXTURED:
            out += [(f[0], TEXTURED[f[1]]), (f[0] + "_tex", "uint")]
        else:
            out.append(f)
    return out


def _layout(fields):
    names, formats, offsets = [], [], []
    off = 0
    align = 4
    for f in expand(fields):
        name, ctype = f[0], f[1]
        count = f[2] if len(f) > 2 else 1
        if ctype in _SCALARS:
            fmt, size, al = _SCALARS[ctype]
            np_fmt = fmt if count == 1 else (fmt, (count,))
        elif ctype in _VECTORS:
            fmt, size, al = _VECTORS[ctype]
            np_fmt = (fmt, (4,)) if count == 1 else (fmt, (count, 4))
        else:
            raise ValueError(f"type {ctype} not allowed in a shared struct")
        off = (off + al - 1) // al * al
        align = max(align, al)
        names.append(name)
        formats.append(np_fmt)
        offsets.append(off)
        off += size * count
    itemsize = (off + align - 1) // align * align
    return names, formats, offsets, itemsize


def plugin_signature() -> tuple:
    """dispatch.signature() of the registry as it stands (whoever assembles the application imports the plugins:
    the loader, the CLI, testing, ...), cached per registry state."""
    return _signature_of(snapshot())


@functools.lru_cache(maxsize=8)
def _signature_of(registrations: tuple) -> tuple:
    # dispatch.signature() walks the whole registry (ms per call); dtype() asks for it for every table row packed
    sig = dispatch.signature()
    if not any(kind == "bsdf" for kind, *_ in sig):
        # rows and programs laid out now would hold no plugin: black renders or C errors far from the cause
        raise RuntimeError("no device plugins are registered: the application imports clrender.plugins (as "
                           "clrender.loader does) before it packs rows or builds programs")
    return sig


def _dtype_of(fields) -> np.dtype:
    names, formats, offsets, itemsize = _layout(fields)
    return np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": itemsize})


def kind_of_row(struct: str) -> dispatch.Kind:
    return next(k for k in dispatch.KINDS.values() if k.struct == struct)


@functools.lru_cache(maxsize=None)
def row_members(struct: str, sig: tuple) -> tuple:
    """The union members of ROWS[struct] for registry signature `sig`: (member name, C struct name, PARAMS, the
    class's name for errors) of each registered plugin with parameters, in tag order."""
    out = []
    for cls in dispatch.plugins(kind_of_row(struct).tag):
        if getattr(cls, "PARAMS", None):  # (a mirror has nothing to store, and C has no empty structs)
            out.append((dispatch.member_of(cls), dispatch.params_struct(cls), tuple(cls.PARAMS), cls.__qualname__))
    return tuple(out)


def union_offset(struct: str) -> int:
    return (_layout(ROWS[struct].header)[3] + 15) // 16 * 16


@functools.lru_cache(maxsize=None)
def _row_dtype(struct: str, sig: tuple) -> np.dtype:
    """A plugin row: header fields, then the union `p` of the plugins' parameters."""
    row = ROWS[struct]
    names, formats, offsets, _ = _layout(row.header)
    for member, _c_name, params, who in row_members(struct, sig):
        sub = _dtype_of(params)
        if sub.itemsize > row.union_bytes:
            raise ValueError(f"{who}: its parameters take {sub.itemsize} bytes; a {struct} row has room "
                             f"for {row.union_bytes}")
        names.append(member)
        formats.append(sub)
        offsets.append(union_offset(struct))
    return np.dtype({"names": names, "formats": formats, "offsets": offsets,
                     "itemsize": union_offset(struct) + row.union_bytes})


def dtype(struct: str) -> np.dtype:
    if struct in ROWS:
        return _row_dtype(struct, plugin_signature())
    return _plain_dtype(struct)


@functools.lru_cache(maxsize=None)
def _plain_dtype(struct: str) -> np.dtype:
    return _dtype_of(STRUCTS[struct])


_ELEMENTS = {"float": (np.float32, ()), "uint": (np.uint32, ()), "ushort": (np.uint16, ()),
             "float2": (np.float32, (2,)), "uint2": (np.uint32, (2,)), "float4": (np.float32, (4,)), "uint4": (np.uint32, (4,))}


def table_element(name: str) -> tuple:
    """(numpy dtype, shape of one element) of SCENE_TABLES entry `name`."""
    types = {n: t for n, t, _ in SCENE_TABLES}
    if name not in types:
        raise KeyError(f"no scene table {name!r}; the tables are {list(types)}")
    t = types[name]
    return _ELEMENTS[t] if t in _ELEMENTS else (dtype(t), ())


def film_element(name: str) -> tuple:
    """(numpy dtype, shape of one element) of FILM_ACCUMULATORS entry `name`."""
    types = {n: t for n, t, *_ in FILM_ACCUMULATORS}
    if name not in types:
        raise KeyError(f"no film accumulator {name!r}; they are {list(types)}")
    return _ELEMENTS[types[name]]


def film_buffers(count_rays: bool = False, splat: bool = False) -> list[tuple[str, bool]]:
    """(name, whether it has one element per pixel) of the accumulators a render allocates: not full, a one-element
    dummy (the ray counters when not counting); a splatting film's only for one."""
    return [(name, when != "count_rays" or count_rays) for name, _t, _what, when in FILM_ACCUMULATORS
            if when != "splat" or splat]


def _film_element_bytes(name: str) -> int:
    dt, shape = film_element(name)
    return np.dtype(dt).itemsize * int(np.prod(shape))


def film_bytes_per_pixel(count_rays: bool = False, splat: bool = False) -> int:
    """Device bytes per pixel of the film's accumulators (with the ray counters when counting, a splatting
    film's own when splatting)."""
    return sum(_film_element_bytes(name) for name, full in film_buffers(count_rays, splat) if full)


def film_bytes(n_pixels: int, count_rays: bool = False, splat: bool = False) -> int:
    """Device bytes of a film of `n_pixels` pixels: film_bytes_per_pixel's, and the one-element dummies."""
    return sum(_film_element_bytes(name) * (n_pixels if full else 1) for name, full in film_buffers(count_rays, splat))


def zeros(struct: str, n: int = 1) -> np.ndarray:
    return np.zeros(n, dtype(struct))
