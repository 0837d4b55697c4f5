"""Scene objects -> SceneBuffers: the flat numpy tables the kernels read (see kernels/scene.h).

This is the only place where Python objects become device data. Shapes are numbered in document order;
BSDFs are shared by identity; area emitters point at their shape and own a slice of the triangle-area CDF
table; the BVH is built over all triangles and spheres together.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from .accel.bvh import build_bvh
from .accel.bvh4 import Bvh4Unsupported, collapse_bvh4
from .accel.primitives import BUILD_OPTIONS, bvh_leaves, pack_leaf_blocks, primitive_bounds
from .device import dispatch, layout
from .device.layout import ENUMS, NONE
from .filters.filter import with_guide
from .textures.texture import TextureTable

log = logging.getLogger("clrender")


@dataclass
class SceneBuffers:
    """The packed scene: one numpy array per table of layout.SCENE_TABLES (``buffers.emitters``, ...), the camera
    row and the filter's sampling table."""
    tables: dict
    camera: np.ndarray
    filter_cdf: np.ndarray
    stats: dict = field(default_factory=dict)
    #: node table layout: 4 (kernels/bvh4.h, the default), 8 (kernels/bvh8.h) or 2 (kernels/bvh.h); the Renderer
    #: passes it to the kernels as BVH_WIDTH
    bvh_width: int = 4

    def __post_init__(self):
        names = [n for n, _, _ in layout.SCENE_TABLES]
        if list(self.tables) != names:
            raise ValueError(f"scene tables must be {names}, got {list(self.tables)}")

    def __getattr__(self, name):
        tables = self.__dict__.get("tables", {})
        if name in tables:
            return tables[name]
        raise AttributeError(name)

    def scene_arrays(self):
        """The tables in kernel-argument order (SCENE_ARGS)."""
        return list(self.tables.values())

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in self.scene_arrays())


class PackContext:
    """Handed to emitter plugins while packing so they can add rows to shared tables."""

    def __init__(self):
        self.cdf_chunks: list[np.ndarray] = []
        self.cdf_size = 0

    def add_cdf(self, values: np.ndarray) -> int:
        off = self.cdf_size
        values = np.asarray(values, np.float32)
        self.cdf_chunks.append(values)
        self.cdf_size += len(values)
        return off


def _nonempty(a: np.ndarray, dtype=None, shape=None) -> np.ndarray:
    """OpenCL has no zero-sized buffers: give empty tables one zero row."""
    if len(a):
        return np.ascontiguousarray(a)
    return np.zeros(shape if shape is not None else (1,) + a.shape[1:], dtype or a.dtype)


DEFAULT_BVH_WIDTH = 4   # kernels/scene.h's default for BVH_WIDTH; measured faster on PoCL (benchmarks/README.md)


def pack_scene(scene, bvh_width: int = DEFAULT_BVH_WIDTH, bvh_options: dict | None = None) -> SceneBuffers:
    """Pack ``scene`` into device tables; ``bvh_width`` 4 (or 8) collapses the binary BVH into 4- (8-)wide nodes
    (falls back to 2 when the tree does not fit the wide kernel, see clrender/accel/bvh4.py); ``bvh_options`` go
    to :func:`clrender.accel.bvh.build_bvh` over BUILD_OPTIONS (e.g. ``max_leaf_size``, ``traversal_cost``)."""
    if bvh_width not in (2, 4, 8):
        raise ValueError(f"bvh_width must be 2, 4 or 8, got {bvh_width}")
    t0 = time.perf_counter()
    shapes = scene.shapes
    bsdf_index: dict[int, int] = {}
    bsdf_rows = []
    shape_rows = layout.zeros("Shape", len(shapes))
    pos_chunks, nrm_chunks, uv_chunks, idx_chunks, tri_chunks = [], [], [], [], []
    spheres, sphere_shape = [], []
    n_vert = 0
    n_tri = 0
    textures = TextureTable()
    for i, sh in enumerate(shapes):
        key = id(sh.bsdf)
        if key not in bsdf_index:
            bsdf_index[key] = len(bsdf_rows)
            bsdf_rows.append(sh.bsdf.pack(textures))
        row = shape_rows[i]
        row["bsdf"] = bsdf_index[key]
        row["emitter"] = NONE
        if sh.is_sphere:
            row["flags"] = ENUMS["SHAPE_SPHERE"]
            row["first"], row["count"] = len(spheres), 1
            spheres.append([*sh.center, sh.radius])
            sphere_shape.append(i)
            continue
        m = sh.mesh
        nv, nf = len(m.positions), len(m.faces)
        flags = 0
        p4 = np.zeros((nv, 4), np.float32)
        p4[:, :3] = m.positions
        pos_chunks.append(p4)
        n4 = np.zeros((nv, 4), np.float32)
        if m.normals is not None:
            flags |= ENUMS["SHAPE_HAS_NORMALS"]
            n4[:, :3] = m.normals
        nrm_chunks.append(n4)
        if m.uvs is not None:
            flags |= ENUMS["SHAPE_HAS_UVS"]
            uv_chunks.append(np.asarray(m.uvs, np.float32))
        else:
            uv_chunks.append(np.zeros((nv, 2), np.float32))
        idx = np.empty((nf, 4), np.uint32)
        idx[:, :3] = m.faces + n_vert
        idx[:, 3] = i
        idx_chunks.append(idx)
        tri_chunks.append(m.positions[m.faces])  # (nf, 3, 3)
        row["flags"] = flags
        row["first"], row["count"] = n_tri, nf
        n_vert += nv
        n_tri += nf

    positions = np.concatenate(pos_chunks) if pos_chunks else np.zeros((0, 4), np.float32)
    normals = np.concatenate(nrm_chunks) if nrm_chunks else np.zeros((0, 4), np.float32)
    uvs = np.concatenate(uv_chunks) if uv_chunks else np.zeros((0, 2), np.float32)
    tri_index = np.concatenate(idx_chunks) if idx_chunks else np.zeros((0, 4), np.uint32)
    tris = np.concatenate(tri_chunks).astype(np.float32) if tri_chunks else np.zeros((0, 3, 3), np.float32)
    sph = np.asarray(spheres, np.float32).reshape(-1, 4)

    # Emitters: area emitters in shape order, then the scene-level ones in document order.
    ctx = PackContext()
    emitter_rows = []
    for i, sh in enumerate(shapes):
        if sh.emitter is not None:
            shape_rows[i]["emitter"] = len(emitter_rows)
            emitter_rows.append(sh.emitter.pack(ctx, shape_index=i, shape=sh, shape_row=shape_rows[i]))
    for em in scene.emitters:
        emitter_rows.append(em.pack(ctx, shape_index=NONE, shape=None, shape_row=None))

    shape_flags = int(np.bitwise_or.reduce(shape_rows["flags"])) if len(shape_rows) else 0
    t_bvh = time.perf_counter()
    lo, hi = primitive_bounds(tris[:, 0], tris[:, 1], tris[:, 2], sph)
    bvh = build_bvh(lo, hi, **{**BUILD_OPTIONS, **(bvh_options or {})})
    prims = pack_leaf_blocks(tris[:, 0], tris[:, 1], tris[:, 2], sph, bvh.order, *bvh_leaves(bvh))
    nodes, node_count = bvh.nodes, bvh.node_count
    if bvh_width in (4, 8):
        try:
            bvh4 = collapse_bvh4(bvh, ENUMS[f"BVH{bvh_width}_STACK_SIZE"], width=bvh_width)
            nodes, node_count = bvh4.nodes, bvh4.node_count
        except Bvh4Unsupported as exc:
            log.warning("using the 2-wide BVH: %s", exc)
            bvh_width = 2
    t_bvh = time.perf_counter() - t_bvh

    info = layout.zeros("SceneInfo")
    info["n_prims"] = len(lo)
    info["n_tris"] = len(tris)
    info["n_spheres"] = len(sph)
    info["n_emitters"] = len(emitter_rows)
    flag_infinite = 1 << dispatch.EMITTER.flags.index("INFINITE")
    infinite = np.array([i for i, r in enumerate(emitter_rows) if r["flags"] & flag_infinite], np.uint32)
    info["n_infinite"] = len(infinite)
    if len(lo):
        bmin, bmax = lo.min(axis=0), hi.max(axis=0)
        c = (bmin + bmax) / 2
        info["bounds_center"][0] = [*c, max(float(np.linalg.norm(bmax - c)), 1e-6)]
    else:
        info["bounds_center"][0] = [0, 0, 0, 1]
    scene.integrator.pack(info[0])
    camera, filter_cdf = scene.camera.pack()
    filter_cdf = with_guide(filter_cdf)     # + the guide that render.cl's filter_sample_guided reads
    emitters = np.array(emitter_rows, layout.dtype("Emitter")) if emitter_rows else layout.zeros("Emitter")
    cdf = np.concatenate(ctx.cdf_chunks) if ctx.cdf_chunks else np.zeros(1, np.float32)
    stats = {
        "triangles": int(len(tris)), "spheres": int(len(sph)), "shapes": len(shapes),
        "emitters": len(emitter_rows), "bvh_nodes": int(node_count), "bvh_depth": int(bvh.depth),
        "bvh_width": bvh_width,
        "bvh_build_seconds": float(t_bvh), "pack_seconds": float(time.perf_counter() - t0),
    }
    tables = dict(
        nodes=_nonempty(nodes), prims=_nonempty(prims), positions=_nonempty(positions),
        # a table no mesh uses is not uploaded (one dummy row): the kernels read it only under its SHAPE_HAS_* flag
        normals=_nonempty(normals if shape_flags & ENUMS["SHAPE_HAS_NORMALS"] else normals[:0]),
        uvs=_nonempty(uvs if shape_flags & ENUMS["SHAPE_HAS_UVS"] else uvs[:0]), tri_index=_nonempty(tri_index),
        spheres=_nonempty(sph), sphere_shape=_nonempty(np.asarray(sphere_shape, np.uint32)),
        shapes=_nonempty(shape_rows), bsdfs=np.array(bsdf_rows, layout.dtype("Bsdf")) if bsdf_rows
        else layout.zeros("Bsdf"), emitters=emitters, emitter_cdf=cdf, textures=textures.array(), infinite=_nonempty(infinite), info=info)
    return SceneBuffers(tables=tables, camera=camera, filter_cdf=filter_cdf, stats=stats, bvh_width=bvh_width)
