"""Scene objects -> SceneBuffers: the flat numpy tables the kernels read (see kernels/scene.h).

This is where Python objects become device data. Shapes are numbered in document order and pack their own
geometry (clrender/shapes/); BSDFs are shared by identity; area emitters point at their shape, which samples its
own surface; plugins append rows to the scene's tables through PackContext.add_table; the BVH is built over all
triangles, spheres and SDF grids' voxels together.
"""
from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field

import numpy as np

from .accel.bvh import build_bvh
from .accel.bvh4 import Bvh4Unsupported, collapse_bvh4
from .accel.primitives import (BUILD_OPTIONS, BUILD_OPTIONS_BY_WIDTH, SdfVoxels, bvh_leaves, leaf_refs,
                               pack_leaf_blocks, primitive_bounds)
from .bsdfs.composite import composite_depth
from .device import dispatch, layout
from .device.layout import ENUMS, NONE
from .errors import SceneError
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
    #: host only: the primitive number at each leaf-order position (triangles first, in the order their meshes
    #: added them, then spheres), for :meth:`triangle_numbers`
    leaf_order: np.ndarray | None = None
    #: the device plugins the tables use (the Renderer builds its program for them); None: unknown (all)
    plugins: dispatch.PluginSet | None = None
    #: the kernels' sample generator: "independent" (Philox) or "sobol" (scrambled Sobol; kernels/rng.h)
    sampler: str = "independent"

    def __post_init__(self):
        names = [n for n, _, _ in layout.SCENE_TABLES]
        if list(self.tables) != names:
            raise ValueError(f"scene tables must be {names}, got {list(self.tables)}")

    def __getattr__(self, name):
        tables = self.__dict__.get("tables", {})
        if name in tables:
            return tables[name]
        raise AttributeError(name)

    @property
    def search_steps(self) -> int:
        """Halvings that find any entry of the tables the kernels search (the CDFs, the mesh table, the filter's
        table): 2^steps exceeds the longest. The render program's CLR_SEARCH_STEPS (kernels/math.h)."""
        longest = max(len(self.tables["cdf"]), len(self.tables["mesh_vertices"]),
                      int(self.camera["filter_bins"][0]) + 1, 1)
        return int(longest).bit_length()

    def scene_arrays(self):
        """The tables in kernel-argument order (SCENE_ARGS)."""
        return list(self.tables.values())

    def triangle_numbers(self, refs) -> np.ndarray:
        """The triangle numbers (each mesh's faces in order, meshes in shape order) of triangles' leaf references
        (what a kernel's Hit.prim / Intersection.tri holds)."""
        pos = np.asarray(refs, np.uint32) >> np.uint32(ENUMS["PRIM_REF_POS_SHIFT"])
        return self.leaf_order[pos.astype(np.int64)]

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in self.scene_arrays())


class PackContext:
    """The scene's tables being packed (layout.SCENE_TABLES): shapes, emitters and textures append their rows with
    add_table and keep the offset they get; pack_scene then reads each table as one array."""

    def __init__(self):
        self._chunks: dict[str, list[np.ndarray]] = {n: [] for n, _, _ in layout.SCENE_TABLES}
        self._sizes = dict.fromkeys(self._chunks, 0)
        self._meshes, self._positions, self._faces = [], [], []
        self._n_vertices = self._n_triangles = 0
        self._sdf_voxels: list[SdfVoxels] = []
        self.textures = TextureTable()
        self.camera_medium = NONE   # the camera's row of the media table (_pack_media)
        self.volumes: dict[int, int] = {}   # rows of the volumes table, by the volume's identity (Volume.pack)
        self.volume_tags: set = set()       # their type tags

    def add_table(self, name: str, dtype: str, rows) -> int:
        """Append `rows` to table `name`, whose element type must be `dtype` as SCENE_TABLES declares it (a
        check that the caller and the kernel agree); returns the offset of the first row."""
        declared = next(t for n, t, _ in layout.SCENE_TABLES if n == name) if name in self._chunks else None
        if declared is None:
            raise KeyError(f"no scene table {name!r}; the tables are {list(self._chunks)}")
        if dtype != declared:
            raise TypeError(f"scene table {name!r} holds {declared}, not {dtype}")
        np_type, shape = layout.table_element(name)
        rows = np.asarray(rows, np_type).reshape((-1,) + shape)
        off = self._sizes[name]
        self._chunks[name].append(rows)
        self._sizes[name] += len(rows)
        return off

    def add_mesh(self, shape_index: int, positions, faces) -> int:
        """Add mesh shape `shape_index`'s vertex positions (V, 3) and triangles (F, 3: indices into them); returns
        its first vertex index, where its rows of the per-vertex tables (normals, uvs) start. The positions and
        triangles stay here: pack_scene puts the vertices into the primitive table and the vertex indices into
        tri_index, both in BVH leaf order, and makes the mesh's mesh_vertices row."""
        base = self._n_vertices
        self._meshes.append((shape_index, base, self._n_triangles, len(faces)))
        self._positions.append(np.asarray(positions, np.float32).reshape(-1, 3))
        self._faces.append(np.asarray(faces, np.int64).reshape(-1, 3) + base)
        self._n_vertices += len(self._positions[-1])
        self._n_triangles += len(faces)
        return base

    def add_sdf_voxels(self, voxels: SdfVoxels) -> None:
        """Add an SDF grid's voxels that hold its surface: pack_scene puts them into the BVH and the primitive
        table."""
        self._sdf_voxels.append(voxels)

    def sdf_voxels(self) -> SdfVoxels:
        return SdfVoxels.concatenate(self._sdf_voxels)

    def meshes(self) -> list[tuple[int, int, int, int]]:
        """(shape index, first vertex, first triangle, triangle count) of each mesh, in the order added."""
        return list(self._meshes)

    def triangles(self) -> np.ndarray:
        """The vertices of every triangle of every mesh, in the order added: float32 (T, 3, 3)."""
        if not self._faces:
            return np.zeros((0, 3, 3), np.float32)
        return np.concatenate(self._positions)[np.concatenate(self._faces)]

    def triangle_vertex_indices(self) -> np.ndarray:
        """The vertex indices of every triangle, in the order added: uint32 (T, 3)."""
        if not self._faces:
            return np.zeros((0, 3), np.uint32)
        return np.concatenate(self._faces).astype(np.uint32)

    def size(self, name: str) -> int:
        return self._sizes[name]

    def array(self, name: str) -> np.ndarray:
        """Table `name` as one contiguous array (OpenCL has no zero-sized buffers: an empty table is one zero row)."""
        np_type, shape = layout.table_element(name)
        chunks = self._chunks[name]
        if not self._sizes[name]:
            return np.zeros((1,) + shape, np_type)
        # filled in place, not np.concatenate: NumPy (1.23+) concatenates structured rows into a packed dtype without
        # their padding (a Phase row came out 20 bytes, not 32, and the kernels read a second row's parameters wrong)
        out = np.zeros((self._sizes[name],) + shape, np_type)
        i = 0
        for c in chunks:
            out[i:i + len(c)] = c
            i += len(c)
        return out


def _nonempty(a: np.ndarray, dtype=None, shape=None) -> np.ndarray:
    """OpenCL has no zero-sized buffers: give empty tables one zero row."""
    if len(a):
        return np.ascontiguousarray(a)
    return np.zeros(shape if shape is not None else (1,) + a.shape[1:], dtype or a.dtype)


DEFAULT_BVH_WIDTH = 8   # kernels/scene.h's default for BVH_WIDTH; measured faster on PoCL (benchmarks/README.md)


EMITTER_SELECTIONS = ("uniform", "power")


def selection_cdf(powers) -> np.ndarray:
    """The light-selection CDF for emitters of the given powers (None: unknown, given the mean of the known ones;
    all zero or unknown: uniform)."""
    known = [p for p in powers if p is not None and np.isfinite(p) and p >= 0]
    fill = float(np.mean(known)) if known else 1.0
    w = np.array([fill if p is None or not (np.isfinite(p) and p >= 0) else p for p in powers], np.float64)
    if not w.sum() > 0:
        w = np.ones(len(w))
    cdf = np.cumsum(w) / w.sum()
    cdf[-1] = 1.0
    return cdf.astype(np.float32)


def pack_scene(scene, bvh_width: int = DEFAULT_BVH_WIDTH, bvh_options: dict | None = None,
               emitter_selection: str | None = None) -> SceneBuffers:
    """Pack ``scene`` into device tables; ``bvh_width`` 4 (or 8) collapses the binary BVH into 4- (8-)wide nodes
    (falls back to 2 when the tree does not fit the wide kernel, see clrender/accel/bvh4.py); ``bvh_options`` go
    to :func:`clrender.accel.bvh.build_bvh` over BUILD_OPTIONS and BUILD_OPTIONS_BY_WIDTH (e.g. ``max_leaf_size``,
    ``traversal_cost``);
    ``emitter_selection``
    ("uniform" or "power"; default: the scene's ``emitter_selection`` attribute, else uniform) is how light
    sampling chooses an emitter (kernels/emitter.h scene_pick_emitter)."""
    if bvh_width not in (2, 4, 8):
        raise ValueError(f"bvh_width must be 2, 4 or 8, got {bvh_width}")
    if emitter_selection is None:
        emitter_selection = getattr(scene, "emitter_selection", "uniform")
    if emitter_selection not in EMITTER_SELECTIONS:
        raise ValueError(f"emitter_selection must be one of {EMITTER_SELECTIONS}, got {emitter_selection!r}")
    t0 = time.perf_counter()
    shapes = scene.shapes
    ctx = PackContext()
    flags = dispatch.flag_defines()
    bsdf_rows, bsdf_of_shape = _pack_materials(shapes, ctx.textures)
    if ctx.textures.bsdf_tables:
        ctx.add_table("bsdf_tables", "BsdfTable", ctx.textures.bsdf_tables_array())
    shape_rows = _pack_shapes(shapes, ctx, bsdf_rows, bsdf_of_shape, flags)
    emitter_rows, emitter_objs = _pack_emitters(scene, ctx, shape_rows)
    media_tags, phase_tags = _pack_media(scene, ctx, shape_rows)
    geo = _pack_geometry(ctx, shape_rows, bvh_width, bvh_options)
    info, infinite = _pack_info(scene, ctx, geo, shape_rows, emitter_rows, emitter_objs, emitter_selection)
    camera, filter_cdf = scene.camera.pack()
    filter_cdf = with_guide(filter_cdf)     # + the guide that render.cl's filter_sample_guided reads
    emitters = _rows_array("Emitter", emitter_rows)
    stats = {
        "triangles": geo.n_tris, "spheres": geo.n_spheres, "sdf_voxels": len(geo.lo) - geo.n_tris - geo.n_spheres,
        "shapes": len(shapes),
        "emitters": len(emitter_rows), "bvh_nodes": int(geo.node_count), "bvh_depth": int(geo.depth),
        "bvh_width": geo.width,
        "bvh_build_seconds": float(geo.seconds), "pack_seconds": float(time.perf_counter() - t0),
    }
    own = dict(nodes=_nonempty(geo.nodes), prims=_nonempty(geo.prims), shapes=_nonempty(shape_rows),
               bsdfs=_rows_array("Bsdf", bsdf_rows),
               emitters=emitters, textures=ctx.textures.array(), infinite=_nonempty(infinite), info=info)
    # Per-vertex normals and uvs are read only where a shape's flags say it has them: when none has, their tables
    # are not uploaded (one zero row; 12 + 8 bytes per vertex saved).
    for table, flag in (("normals", "SHAPE_HAS_NORMALS"), ("uvs", "SHAPE_HAS_UVS")):
        if not np.any(shape_rows["flags"] & flags[flag]):
            own[table] = ctx.array(table)[:1] * 0
    tables = {name: own[name] if name in own else ctx.array(name) for name, _, _ in layout.SCENE_TABLES}
    stats["device_bytes"] = int(sum(a.nbytes for a in tables.values()))
    # Tags from the real rows only (an empty table's zero row and texel rows are not plugins).
    used = dispatch.PluginSet.from_tags(
        {"bsdf": {int(r["type"]) for r in bsdf_rows}, "mesh": set(shape_rows["type"].tolist()),
         "emitter": {int(r["type"]) for r in emitter_rows}, "texture": ctx.textures.tags,
         "rfilter": {int(camera[0]["filter_type"])}, "medium": media_tags, "phase": phase_tags,
         "volume": ctx.volume_tags},
        {"bsdf": max((composite_depth(b) for b in {id(s.bsdf): s.bsdf for s in shapes}.values()), default=0)})
    return SceneBuffers(tables=tables, camera=camera, filter_cdf=filter_cdf, stats=stats, bvh_width=geo.width,
                        leaf_order=np.asarray(geo.order, np.int64), plugins=used,
                        sampler=getattr(getattr(scene, "sampler", None), "generator", "independent"))


def _rows_array(struct: str, rows) -> np.ndarray:
    """Rows as one array of `struct` (one zero row if none). Assigned into zeros: np.array of records copies them
    member by member and leaves the bytes no member covers undefined, and packed_hash reads every byte."""
    out = layout.zeros(struct, max(len(rows), 1))
    if rows:
        out[:] = rows
    return out


def _pack_materials(shapes, textures: TextureTable) -> tuple[list, list[int]]:
    """The BSDF rows, each BSDF packed once however many shapes share it (by identity), and each shape's first
    row. BSDFs add only to the texture table, so they pack before the shapes fill the others."""
    first: dict[int, int] = {}
    rows, of_shape = [], []
    for sh in shapes:
        key = id(sh.bsdf)
        if key not in first:
            first[key] = len(rows)
            rows.extend(sh.bsdf.pack_rows(textures))
        of_shape.append(first[key])
    return rows, of_shape


def _pack_shapes(shapes, ctx: PackContext, bsdf_rows, bsdf_of_shape, flags) -> np.ndarray:
    """The shape rows (each shape packs its own geometry into ctx), numbered in document order."""
    shape_rows = layout.zeros("Shape", len(shapes))
    for i, sh in enumerate(shapes):
        row = shape_rows[i]
        row["bsdf"] = bsdf_of_shape[i]
        row["emitter"] = NONE
        sh.pack(ctx, i, row)
        if bsdf_rows[row["bsdf"]]["flags"] & flags["BSDF_UV"]:
            row["flags"] |= flags["SHAPE_NEEDS_UV"]
    return shape_rows


def _pack_media(scene, ctx: PackContext, shape_rows) -> tuple[set, set]:
    """The `media` and `phases` tables: each medium that a shape (interior, exterior) or the camera holds, packed
    once however many hold it (by identity), its phase function likewise; the shapes' interior/exterior and
    ctx.camera_medium get their rows (NONE: vacuum). Returns the type tags used (media, phases)."""
    media: dict[int, int] = {}
    phases: dict[int, int] = {}
    tags: tuple[set, set] = (set(), set())

    def row_of(medium) -> int:
        if medium is None:
            return NONE
        if id(medium) not in media:
            phase = medium.phase
            if id(phase) not in phases:
                prow = phase.pack()
                phases[id(phase)] = ctx.add_table("phases", "Phase", prow)
                tags[1].add(int(prow["type"]))
            mrow = medium.pack(phases[id(phase)], ctx)
            media[id(medium)] = ctx.add_table("media", "Medium", mrow)
            tags[0].add(int(mrow["type"]))
        return media[id(medium)]

    for i, sh in enumerate(scene.shapes):
        shape_rows[i]["interior"] = row_of(getattr(sh, "interior", None))
        shape_rows[i]["exterior"] = row_of(getattr(sh, "exterior", None))
    ctx.camera_medium = row_of(getattr(scene.camera, "medium", None))
    spec = getattr(scene.integrator, "spec", None)
    if media and getattr(spec, "type", None) == "prbvolpath":
        raise SceneError('<integrator type="prbvolpath"> renders forward as path, which would ignore the scene\'s '
                         'participating media: render media with volpath or volpathmis', spec.location)
    return tags


def _pack_emitters(scene, ctx: PackContext, shape_rows) -> tuple[list, list]:
    """Emitter rows: area emitters in shape order (their shape rows point at them), then the scene-level ones in
    document order (each as the rows of its parts(): a sunsky is a sky and a sun); and (emitter, shape index or None)
    for each row."""
    emitter_rows, emitter_objs = [], []
    for i, sh in enumerate(scene.shapes):
        if sh.emitter is not None:
            shape_rows[i]["emitter"] = len(emitter_rows)
            emitter_rows.append(sh.emitter.pack(ctx, shape_index=i, shape=sh, shape_row=shape_rows[i]))
            emitter_objs.append((sh.emitter, i))
    for em in (part for e in scene.emitters for part in e.parts()):
        emitter_rows.append(em.pack(ctx, shape_index=NONE, shape=None, shape_row=None))
        emitter_objs.append((em, None))
    return emitter_rows, emitter_objs


@dataclass
class _Geometry:
    """The BVH over every primitive and what the other tables need of it."""
    lo: np.ndarray          # (P, 3) primitive bounds, triangles first
    hi: np.ndarray
    n_tris: int
    n_spheres: int
    prims: np.ndarray       # the primitive table in leaf order
    nodes: np.ndarray
    node_count: int
    depth: int
    order: np.ndarray       # the primitive number at each leaf-order position
    width: int              # the node layout it got (2 where a wide one does not fit)
    seconds: float          # the BVH's build time


def _pack_geometry(ctx: PackContext, shape_rows, bvh_width: int, bvh_options: dict | None) -> _Geometry:
    """The BVH over every triangle (numbered as the meshes added them), every sphere and every SDF voxel; the
    primitive table, and the tri_index, mesh_vertices and tri_refs tables in its leaf order."""
    tris = ctx.triangles()
    sph = ctx.array("spheres")[:ctx.size("spheres")]
    vox = ctx.sdf_voxels()

    t_bvh = time.perf_counter()
    with np.errstate(over="ignore", invalid="ignore"):
        lo, hi = primitive_bounds(tris[:, 0], tris[:, 1], tris[:, 2], sph, vox)
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        # The shapes check their own extent; this guards the build (an infinite box makes its binning allocate
        # without bound) against any that does not.
        raise SceneError("a shape reaches beyond the largest single-precision number (about 3.4e38): the "
                         "scene's bounding boxes are not finite")
    bvh = build_bvh(lo, hi, **{**BUILD_OPTIONS, **BUILD_OPTIONS_BY_WIDTH.get(bvh_width, {}), **(bvh_options or {})})
    leaves = bvh_leaves(bvh)
    # A hit names its triangle by leaf reference (where its vertices are in the primitive table, the only copy
    # on the device); tri_index holds the vertex indices by leaf-order position too.
    try:
        refs = leaf_refs(*leaves)
    except ValueError as exc:
        raise SceneError(f"the scene is too large for the device tables: {exc}") from None
    on_tri = bvh.order < len(tris)
    tri_ref = np.empty(len(tris), np.uint32)
    tri_ref[bvh.order[on_tri]] = refs[on_tri]
    prims = pack_leaf_blocks(tris[:, 0], tris[:, 1], tris[:, 2], sph, bvh.order, *leaves, tri_ids=tri_ref,
                             voxels=vox)
    tri_index = np.full((len(lo), 3), NONE, np.uint32)
    tri_index[on_tri] = ctx.triangle_vertex_indices()[bvh.order[on_tri]]
    ctx.add_table("tri_index", "uint", tri_index)
    for shape, first_vertex, first_tri, count in ctx.meshes():
        ctx.add_table("mesh_vertices", "uint2", [first_vertex, shape])
        if shape_rows[shape]["emitter"] != NONE:     # mesh_sample picks its triangles by leaf reference
            shape_rows[shape]["first"] = ctx.add_table("tri_refs", "uint", tri_ref[first_tri:first_tri + count])
    nodes, node_count = bvh.nodes, bvh.node_count
    if bvh_width in (4, 8):
        try:
            bvh4 = collapse_bvh4(bvh, ENUMS[f"BVH{bvh_width}_STACK_SIZE"], width=bvh_width)
            nodes, node_count = bvh4.nodes, bvh4.node_count
        except Bvh4Unsupported as exc:
            log.warning("using the 2-wide BVH: %s", exc)
            bvh_width = 2
    return _Geometry(lo=lo, hi=hi, n_tris=int(len(tris)), n_spheres=int(len(sph)), prims=prims, nodes=nodes,
                     node_count=node_count, depth=bvh.depth, order=bvh.order, width=bvh_width,
                     seconds=time.perf_counter() - t_bvh)


def _pack_info(scene, ctx: PackContext, geo: _Geometry, shape_rows, emitter_rows, emitter_objs,
               emitter_selection: str) -> tuple[np.ndarray, np.ndarray]:
    """The SceneInfo row (counts, bounding sphere, light-selection CDF, the integrator's parameters) and the
    table of infinite emitters."""
    info = layout.zeros("SceneInfo")
    info["n_prims"] = len(geo.lo)
    info["n_tris"] = geo.n_tris
    info["n_spheres"] = geo.n_spheres
    info["n_meshes"] = len(ctx.meshes())
    info["n_emitters"] = len(emitter_rows)
    flag_infinite = 1 << dispatch.EMITTER.flags.index("INFINITE")
    infinite = np.array([i for i, r in enumerate(emitter_rows) if r["flags"] & flag_infinite], np.uint32)
    info["n_infinite"] = len(infinite)
    if len(geo.lo):
        bmin, bmax = geo.lo.min(axis=0), geo.hi.max(axis=0)
        c = (bmin + bmax) / 2
        info["bounds_center"][0] = [*c, max(float(np.linalg.norm(bmax - c)), 1e-6)]
    else:
        info["bounds_center"][0] = [0, 0, 0, 1]
    info["emitter_cdf"] = NONE
    if emitter_selection == "power" and emitter_rows:
        radius = float(info["bounds_center"][0][3])
        powers = [em.selection_power(radius, float(shape_rows[i]["area"]) if i is not None else 0.0)
                  for em, i in emitter_objs]
        info["emitter_cdf"] = ctx.add_table("cdf", "float", selection_cdf(powers))
    info["n_media"] = ctx.size("media")
    info["camera_medium"] = ctx.camera_medium
    scene.integrator.pack(info[0])
    return info, infinite
