"""The one source of truth for every struct shared by the host and the kernels.

Each struct is declared once here as a list of (field, C type[, count]). From that we derive both the numpy
dtype (explicit offsets, C alignment: a float4/uint4 is 16-byte aligned) used to pack tables on the host, and
the C ``typedef struct`` text that ``program.build_program`` prepends to every kernel source. Only 4-byte
scalars and 16-byte vectors are allowed: ``float3`` is 16 bytes on the device and 12 in numpy, so it never
appears in a buffer. ``tests/test_layout.py`` compiles a probe kernel and compares sizeof/offsetof.
"""
from __future__ import annotations

import functools

import numpy as np

_SCALARS = {"float": ("<f4", 4, 4), "uint": ("<u4", 4, 4), "int": ("<i4", 4, 4)}
_VECTORS = {"float4": ("<f4", 16, 16), "uint4": ("<u4", 16, 16)}

NONE = 0xFFFFFFFF  # "no index" in uint fields (no emitter, no texture, ...)

BSDF_TABLE_SIZE = 64  # entries of a BsdfTable (kernels: BSDF_TABLE_SIZE)

# Structs with no plugins behind them (the shape, BSDF, emitter, texture, integrator and camera rows are the
# UNION_STRUCTS below).
STRUCTS: dict[str, list[tuple]] = {
    # a BSDF's lookup table on BSDF_TABLE_SIZE uniform nodes (roughplastic's coating transmittance T(mu)); its row
    # holds the index, so a row stays the size of the other BSDFs' parameters
    "BsdfTable": [("values", "float", BSDF_TABLE_SIZE)],
}
# The scene's tables, in kernel-argument order: (name, element type, what it holds). The kernels' SceneData
# struct, its SCENE_ARGS argument list (each table is the argument s_<name>) and SCENE_INIT are generated from
# this list; clrender.pack.SceneBuffers holds one numpy array per entry, and the host sets them by name.
SCENE_TABLES: list[tuple[str, str, str]] = [
    ("nodes", "float4", "BVH nodes (2-, 4- or 8-wide layout, see BVH_WIDTH)"),
    ("prims", "float4", "primitives in BVH leaf order, 10 words each in blocks of up to 4 (triangles' vertices, "
                        "spheres), clrender/accel/primitives.py pack_leaf_blocks; the only copy of the vertices"),
    ("normals", "ushort", "per vertex, x y z as IEEE half floats (meshes with SHAPE_HAS_NORMALS; "
                          "clrender/shapes/trianglemesh.py half_normals)"),
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
    ("info", "SceneInfo", "scene-wide numbers and the integrator's parameters"),
]

# Bsdf and Emitter rows are generated from the registered plugins (clrender/device/dispatch.py): the kind's
# header fields, then a union `p` of every plugin's declared parameter struct.
# SceneInfo: scene-wide numbers + the integrator's parameters; Camera: the camera + its filter's parameters.
UNION_STRUCTS = ("Camera", "Texture", "Shape", "Bsdf", "Emitter", "SceneInfo")


# Type tags and flag bits, shared the same way (emitted as #defines).
ENUMS: dict[str, int] = {
    "BSDF_TABLE_SIZE": BSDF_TABLE_SIZE,
    # BVH encodings shared by the builders (clrender/accel) and the traversals (kernels/bvh*.h)
    "BVH_LEAF_BIT": 0x80000000,       # a node reference to a leaf
    "BVH_SPHERE_BIT": 0x80000000,     # a primitive id of an analytic sphere
    "BVH_STACK_SIZE": 64,             # 2-wide traversal stack (the builder keeps the depth below it)
    "BVH4_STACK_SIZE": 64,            # 4-wide traversal stack (the collapse checks the tree needs no more)
    "BVH8_STACK_SIZE": 96,            # 8-wide traversal stack (likewise)
    "BVH4_COUNT_SHIFT": 27,           # 4-wide leaf reference: LEAF_BIT | (count - 1) << 27 | first
    "BVH4_MAX_LEAF_COUNT": 16,
    # A triangle's leaf reference, the id word of its lane in the primitive table (so Hit.prim): its leaf-order
    # position pos, its lane l in its block and the block's size c, as pos << 4 | l << 2 | (c - 1); the block
    # starts at pos - l, so the kernels find its vertices there (kernels/shapes/mesh.h mesh_triangle)
    "PRIM_REF_POS_SHIFT": 4,
    "PRIM_REF_MAX_POS": (1 << 27) - 1,
}


def _expand(fields):
    """A "texture" parameter is a constant colour and the index of a texture row (NONE: the constant)."""
    out = []
    for f in fields:
        if f[1] == "texture":
            out += [(f[0], "float4"), (f[0] + "_tex", "uint")]
        else:
            out.append(f)
    return out


def _layout(fields):
    names, formats, offsets, c_lines = [], [], [], []
    off = 0
    align = 4
    fields = _expand(fields)
    for f in fields:
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
        c_lines.append(f"    {ctype} {name}{f'[{count}]' if count > 1 else ''};")
        off += size * count
    itemsize = (off + align - 1) // align * align
    return names, formats, offsets, itemsize, c_lines


def _signature() -> tuple:
    from .. import plugins  # noqa: F401  (registers every plugin before the registry is read)
    from ..scene.registry import snapshot

    return _signature_of(snapshot())


@functools.lru_cache(maxsize=8)
def _signature_of(registrations: tuple) -> tuple:
    # dispatch.signature() walks the whole registry (ms per call); dtype() asks for it for every table row packed
    from .dispatch import signature

    return signature()


def _plain_dtype(fields) -> np.dtype:
    names, formats, offsets, itemsize, _ = _layout(fields)
    return np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": itemsize})


@functools.lru_cache(maxsize=None)
def _union_layout(struct: str, sig: tuple):
    """(numpy dtype, C text) of a plugin row: header fields, then the union `p` of the plugins' parameters."""
    from .dispatch import KINDS, member_of, params_struct, plugins

    kind = next(k for k in KINDS.values() if k.struct == struct)
    names, formats, offsets, size, c_lines = _layout(kind.header)
    union_off = (size + 15) // 16 * 16
    c_types, members = [], []
    for cls in plugins(kind.tag):
        if not getattr(cls, "PARAMS", None):
            continue  # e.g. a mirror: nothing to store (C has no empty structs)
        p_names, p_formats, p_offsets, p_size, p_lines = _layout(cls.PARAMS)
        if p_size > kind.param_bytes:
            raise ValueError(f"{cls.__qualname__}: its parameters take {p_size} bytes; a {struct} row has room "
                             f"for {kind.param_bytes}")
        sub = np.dtype({"names": p_names, "formats": p_formats, "offsets": p_offsets, "itemsize": p_size})
        names.append(member_of(cls))
        formats.append(sub)
        offsets.append(union_off)
        c_types.append("typedef struct {\n" + "\n".join(p_lines) + f"\n}} {params_struct(cls)};")
        members.append(f"        {params_struct(cls)} {member_of(cls)};")
    dt = np.dtype({"names": names, "formats": formats, "offsets": offsets,
                   "itemsize": union_off + kind.param_bytes})
    c = "\n".join(c_types) + "\ntypedef struct {\n" + "\n".join(c_lines) + "\n    union {\n" + "\n".join(members)
    c += f"\n        float4 _size[{kind.param_bytes // 16}];  /* fixes the row size whatever is registered */"
    c += f"\n    }} p;\n}} {struct};"
    return dt, c


def _scene_tables_c() -> str:
    fields = [f"    __global const {t}* {n};  /* {what} */" for n, t, what in SCENE_TABLES]
    out = ["typedef struct {", *fields,
           "#ifdef CLRENDER_COUNT_RAYS",
           "    uint n_closest, n_shadow;  /* rays traced by this work-item (benchmark builds only) */",
           "#endif", "} SceneData;"]
    args = ", ".join(f"__global const {t}* s_{n}" for n, t, _ in SCENE_TABLES)
    init = " ".join(f"sd.{n} = s_{n};" for n, _, _ in SCENE_TABLES)
    out.append(f"#define SCENE_ARGS {args}")
    out.append(f"#define SCENE_INIT(sd) SceneData sd; {init} SCENE_INIT_COUNTERS(sd)")
    return "\n".join(out)


def dtype(struct: str) -> np.dtype:
    if struct in UNION_STRUCTS:
        return _union_layout(struct, _signature())[0]
    return _plain_dtype_cached(struct)


@functools.lru_cache(maxsize=None)
def _plain_dtype_cached(struct: str) -> np.dtype:
    return _plain_dtype(STRUCTS[struct])


_ELEMENTS = {"float": (np.float32, ()), "uint": (np.uint32, ()), "ushort": (np.uint16, ()),
             "float2": (np.float32, (2,)), "uint2": (np.uint32, (2,)), "float4": (np.float32, (4,)), "uint4": (np.uint32, (4,))}


def table_element(name: str) -> tuple:
    """(numpy dtype, shape of one element) of SCENE_TABLES entry `name`."""
    types = {n: t for n, t, _ in SCENE_TABLES}
    if name not in types:
        raise KeyError(f"no scene table {name!r}; the tables are {list(types)}")
    t = types[name]
    return _ELEMENTS[t] if t in _ELEMENTS else (dtype(t), ())


def zeros(struct: str, n: int = 1) -> np.ndarray:
    return np.zeros(n, dtype(struct))


def c_header() -> str:
    return _c_header(_signature())


@functools.lru_cache(maxsize=None)
def _c_header(sig: tuple) -> str:
    from .dispatch import flag_defines

    out = ["#ifndef CLRENDER_TYPES_GEN", "#define CLRENDER_TYPES_GEN",
           "/* generated from clrender/device/layout.py: do not edit */"]
    for name, fields in STRUCTS.items():
        *_, lines = _layout(fields)
        out.append("typedef struct {")
        out.extend(lines)
        out.append(f"}} {name};")
    for name in UNION_STRUCTS:
        out.append(_union_layout(name, sig)[1])
    out.append(_scene_tables_c())
    out.append(f"#define NONE 0x{NONE:08X}u")
    out.extend(f"#define {k} {v}u" for k, v in ENUMS.items())
    out.extend(f"#define {k} {v}u" for k, v in flag_defines().items())
    out.append("#endif")
    return "\n".join(out) + "\n"
