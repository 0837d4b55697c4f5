"""Running BSDFs and warps on the device, in bulk, for statistical tests.

Every helper builds its program once per context (``program.build_program`` caches), launches with one
fixed local size (64) and a global size padded to a multiple of it and to at least MIN_GLOBAL, and splits large
batches into launches of at most ``CHUNK`` work-items so each stays short. Random numbers come from the counter-based Sampler of
kernels/rng.h keyed by (seed, global sample index, 0), so a batch is reproducible however it is split.

The BSDF helpers take any Bsdf row from a plugin's ``.pack()`` (or an array of rows plus a per-sample
row index, to run many cases in one launch). Their program holds only the plugins those rows use (``rows_plugins``:
the BSDFs' tags, the composites' nesting depth and the textures the side table holds), as a render program holds
only its scene's: a program with every plugin takes minutes to compile on 2 cores, one with a plugin or two
seconds. ``defines=ALL_PLUGINS`` builds the one with every plugin.
"""
from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass

import numpy as np

from .. import plugins  # noqa: F401  (the rows' tags are numbered over every registered plugin)
from ..device import codegen, dispatch, layout
from ..device.program import MIN_GENERIC_GLOBAL, build_program

LOCAL = 64
CHUNK = 1 << 20
# CLRENDER_TEST_FAST_MATH=1 builds these programs with -cl-fast-relaxed-math (as a renderer may run).
FAST_MATH = os.environ.get("CLRENDER_TEST_FAST_MATH", "") not in ("", "0")

BSDF_SRC = '#include "testing/bsdf_batch.cl"\n'  # kernels/testing/bsdf_batch.cl


def _cl():
    import pyopencl as cl

    return cl


def _program(ctx, source=BSDF_SRC, defines=None):
    return build_program(ctx, source, defines, fast_math=FAST_MATH)


_KERNELS: dict = {}


def _kernel(ctx, name, source=BSDF_SRC, defines=None):
    key = (ctx.int_ptr, name, source, tuple(sorted((defines or {}).items())), FAST_MATH, codegen.c_header())
    k = _KERNELS.get(key)
    if k is None:
        k = _KERNELS[key] = _cl().Kernel(_program(ctx, source, defines), name)
    return k


MIN_GLOBAL = MIN_GENERIC_GLOBAL   # one compiled work-group function per kernel (device/program.py)


def padded(n: int, local: int = LOCAL) -> int:
    return max(MIN_GLOBAL, (n + local - 1) // local * local)


class BsdfRows(np.ndarray):
    """Bsdf rows carrying the texture and bsdf_tables rows they index (made by :func:`pack_rows`); the batch
    functions use those unless given others. `plugins`: the PluginSet they use, exactly (the BSDF's composite depth
    and its texture table's tags, which the rows alone tell only as bounds)."""

    def __array_finalize__(self, obj):
        self.textures = getattr(obj, "textures", None)
        self.tables = getattr(obj, "tables", None)
        self.plugins = getattr(obj, "plugins", None)


def pack_rows(bsdf) -> BsdfRows:
    """A lone BSDF's rows (its own first, then its children's, Bsdf.pack_rows) with their own side tables."""
    from ..bsdfs.composite import composite_depth
    from ..textures.texture import TextureTable

    table = TextureTable()
    rows = np.array(bsdf.pack_rows(table), layout.dtype("Bsdf")).view(BsdfRows)
    rows.textures, rows.tables = table.array(), table.bsdf_tables_array()
    rows.plugins = dispatch.PluginSet.from_tags({"bsdf": {int(t) for t in rows["type"]}, "texture": table.tags},
                                                {"bsdf": composite_depth(bsdf)})
    return rows


#: `defines` of a test program holding every registered plugin (as a build without a plugin set does)
ALL_PLUGINS = {dispatch.ALL_PLUGINS: None}


def _known(kind: str, tags) -> set:
    """The tags that name a registered plugin of `kind` (any other takes the methods' default in every program)."""
    n = len(dispatch.plugins(kind))
    return {int(t) for t in np.atleast_1d(tags) if 0 <= int(t) < n}


def rows_plugins(bsdf_rows, textures=None) -> dispatch.PluginSet:
    """The plugins a batch of `bsdf_rows` may reach: their BSDF tags; composites nested as deep as the rows have
    composite rows (a bound: a chain of d nested composites is d rows; ``pack_rows`` records the exact depth); and
    the texture plugins whose tags appear in the `textures` table. That table also holds texel rows, whose first
    word is pixel data: read as a tag it may add a texture plugin the rows do not use, never leave one out.
    Rows made by ``pack_rows`` (with their own textures) carry their exact set."""
    own = getattr(bsdf_rows, "plugins", None)
    if own is not None and (textures is None or textures is getattr(bsdf_rows, "textures", None)):
        return own
    rows = _rows(bsdf_rows)
    tags = _known("bsdf", rows["type"])
    classes = dispatch.plugins("bsdf")
    composites = sum(dispatch.is_composite(classes[int(t)]) for t in rows["type"] if int(t) in tags)
    if textures is None:
        textures = getattr(bsdf_rows, "textures", None)
    tex = set()
    if textures is not None:
        t = np.atleast_1d(np.asarray(textures, layout.dtype("Texture")))
        # all-zero rows (the placeholder of an empty table, black texels) would read as tag 0, a bitmap, whose
        # real rows are never all zero (they hold the image's size)
        tex = _known("texture", t["type"][np.any(t.view(np.uint8).reshape(len(t), -1) != 0, axis=1)])
    return dispatch.PluginSet.from_tags({"bsdf": tags, "texture": tex},
                                        {"bsdf": min(composites, dispatch.BSDF.composite_levels)})


def plugin_set(bsdfs=(), textures=(), levels: int = 0) -> dispatch.PluginSet:
    """The PluginSet of BSDF and texture plugins named by prefix (`diffuse`, `checkerboard_color`), with composites
    nested `levels` deep."""
    out = set()
    for kind, names in (("bsdf", bsdfs), ("texture", textures)):
        known = {dispatch.prefix_of(c) for c in dispatch.plugins(kind)}
        unknown = set(names) - known
        if unknown:
            raise ValueError(f"no {kind} plugin {sorted(unknown)}; known: {sorted(known)}")
        out |= {(kind, n) for n in names}
    return dispatch.PluginSet(frozenset(out), (("bsdf", int(levels)),))


def union(a: dispatch.PluginSet, b: dispatch.PluginSet) -> dispatch.PluginSet:
    """Both sets' plugins, each kind's composites as deep as the deeper set's."""
    levels = dict(a.levels)
    for kind, depth in b.levels:
        levels[kind] = max(levels.get(kind, 0), depth)
    return dispatch.PluginSet(a.used | b.used, tuple(sorted(levels.items())))


_HOLDING: list = []   # the sets that programs_holding() adds to every program built now


@contextlib.contextmanager
def programs_holding(plugins: dispatch.PluginSet):
    """Within it, every test program built for rows (no `defines` given) also holds `plugins`. A test file whose
    cases use different subsets of its plugins (a bumpmap over four children, textured and plain rows) then
    compiles one program for them all instead of one per subset (tests/bsdfs/conftest.py: a file's PROGRAM)."""
    _HOLDING.append(plugins)
    try:
        yield
    finally:
        _HOLDING.pop()


def _defines(bsdf_rows, textures, defines) -> dict:
    if defines is not None:
        return defines
    s = rows_plugins(bsdf_rows, textures)
    for extra in _HOLDING:
        s = union(s, extra)
    return s.defines()


def _rows(bsdf_rows) -> np.ndarray:
    rows = np.atleast_1d(np.asarray(bsdf_rows))
    if rows.dtype != layout.dtype("Bsdf"):
        rows = rows.astype(layout.dtype("Bsdf"))
    return np.ascontiguousarray(rows)


def _per_item(x, n, width, dtype=np.float32):
    a = np.asarray(x, np.float64)
    if a.ndim == 1:
        a = np.broadcast_to(a, (n, a.shape[0]))
    out = np.zeros((n, width), dtype)
    out[:, :a.shape[1]] = a
    return out


@dataclass
class BsdfSamples:
    """One bsdf_sample per entry: wo (n,3), weight = f cos/pdf (n,3), pdf = bsdf_pdf(wi, wo) (n,),
    measure (n,), eta (n,) and f = bsdf_eval(wi, wo) (n,3). Unpacks as (wo, weight, pdf, measure)."""
    wo: np.ndarray
    weight: np.ndarray
    pdf: np.ndarray
    measure: np.ndarray
    eta: np.ndarray
    f: np.ndarray

    def __iter__(self):
        return iter((self.wo, self.weight, self.pdf, self.measure))


#: the surface derivatives a query gets by default: dp/du = x, dp/dv = y, geometric normal z (and dp/du in world
#: space = x: the shading frame is the world's)
GEOMETRY = np.array([[1.0, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0]])


def _geometry(geometry, n):
    g = np.broadcast_to(np.asarray(GEOMETRY if geometry is None else geometry, np.float64), (n, 4, 3))
    out = np.zeros((n, 4, 4), np.float32)
    out[..., :3] = g
    return out.reshape(n * 4, 4)


def _side_table(ctx, struct, rows):
    """A table the rows refer to: textures (a plugin's `bsdf.pack()` leaves them in `bsdf.textures_table`) or
    bsdf_tables (`bsdf.bsdf_tables`); one zero row if none."""
    cl = _cl()
    t = layout.zeros(struct) if rows is None or len(rows) == 0 else np.asarray(rows, layout.dtype(struct))
    return cl.Buffer(ctx, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(t))


def bsdf_sample_batch(ctx, queue, bsdf_row, wi, n: int, seed: int = 0, uv=(0.5, 0.5), row_index=None,
                      first: int = 0, textures=None, defines=None, geometry=None, tables=None) -> BsdfSamples:
    """n calls of bsdf_sample on the device. `bsdf_row`: one packed row or an array of rows (then
    `row_index` (n,) picks each sample's row); `wi`: (3,) or (n,3) in the local frame (normalised here);
    `uv`: (2,) or (n,2); `textures`, `tables`: the texture and bsdf_tables rows the rows index (a lone plugin's
    `pack()` leaves them in `textures_table` and `bsdf_tables`); `defines`: of the program (default: the plugin
    set of the rows and textures, ``rows_plugins``, with any ``programs_holding`` adds; ALL_PLUGINS: every
    plugin); `geometry`: (4, 3) or (n, 4, 3), the query's dp/du, dp/dv, geometric normal and world dp/du
    (GEOMETRY by default). Sample i uses the Sampler stream (seed, first + i, 0)."""
    cl = _cl()
    rows = _rows(bsdf_row)
    wi = np.asarray(wi, np.float64)
    wi = wi / np.linalg.norm(wi, axis=-1, keepdims=True)
    args = _per_item(wi, n, 4)
    idx = np.zeros(n, np.uint32) if row_index is None else np.asarray(row_index, np.uint32)
    if idx.shape != (n,) or (n and idx.max() >= len(rows)):
        raise ValueError("row_index must be (n,) indices into bsdf_row")
    args[:, 3] = idx.view(np.float32)
    uvs = _per_item(uv, n, 2)
    geo = _geometry(geometry, n)
    textures = getattr(bsdf_row, "textures", None) if textures is None else textures
    k = _kernel(ctx, "bsdf_sample_batch", defines=_defines(bsdf_row, textures, defines))
    mf = cl.mem_flags
    d_rows = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=rows)
    d_tex = _side_table(ctx, "Texture", textures)
    d_tables = _side_table(ctx, "BsdfTable", getattr(bsdf_row, "tables", None) if tables is None else tables)
    out = BsdfSamples(np.empty((n, 3), np.float32), np.empty((n, 3), np.float32), np.empty(n, np.float32),
                      np.empty(n, np.uint32), np.empty(n, np.float32), np.empty((n, 3), np.float32))
    for s in range(0, n, CHUNK):
        m = min(CHUNK, n - s)
        g = padded(m)
        d_args = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(args[s:s + m]))
        d_uv = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(uvs[s:s + m]))
        d_geo = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(geo[4 * s:4 * (s + m)]))
        wo = np.empty((m, 4), np.float32)
        w = np.empty((m, 4), np.float32)
        f = np.empty((m, 4), np.float32)
        pdf = np.empty(m, np.float32)
        meas = np.empty(m, np.uint32)
        bufs = [cl.Buffer(ctx, mf.WRITE_ONLY, a.nbytes) for a in (wo, w, f, pdf, meas)]
        k(queue, (g,), (LOCAL,), d_rows, d_tex, d_tables, d_args, d_uv, d_geo, np.uint32(m), np.uint32(first + s),
          np.uint32(seed), *bufs)
        for a, b in zip((wo, w, f, pdf, meas), bufs):
            cl.enqueue_copy(queue, a, b)
        queue.finish()
        out.wo[s:s + m] = wo[:, :3]
        out.eta[s:s + m] = wo[:, 3]
        out.weight[s:s + m] = w[:, :3]
        out.f[s:s + m] = f[:, :3]
        out.pdf[s:s + m] = pdf
        out.measure[s:s + m] = meas
    return out


def bsdf_pdf_eval_batch(ctx, queue, bsdf_row, wi, wo, uv=(0.5, 0.5), row_index=None, with_albedo=False,
                        textures=None, geometry=None, tables=None, defines=None):
    """bsdf_pdf and bsdf_eval at m direction pairs: wi (3,) or (m,3), wo (m,3). Returns (pdf (m,), f (m,3)),
    plus bsdf_albedo(uv) (m,3) if `with_albedo`. Other arguments as bsdf_sample_batch's."""
    cl = _cl()
    rows = _rows(bsdf_row)
    wo = np.asarray(wo, np.float64).reshape(-1, 3)
    m = len(wo)
    wi_a = _per_item(np.asarray(wi, np.float64), m, 4)
    idx = np.zeros(m, np.uint32) if row_index is None else np.asarray(row_index, np.uint32)
    wi_a[:, 3] = idx.view(np.float32)
    wo_a = _per_item(wo, m, 4)
    uvs = _per_item(uv, m, 2)
    geo = _geometry(geometry, m)
    textures = getattr(bsdf_row, "textures", None) if textures is None else textures
    k = _kernel(ctx, "bsdf_pdf_eval_batch", defines=_defines(bsdf_row, textures, defines))
    mf = cl.mem_flags
    d_rows = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=rows)
    d_tex = _side_table(ctx, "Texture", textures)
    d_tables = _side_table(ctx, "BsdfTable", getattr(bsdf_row, "tables", None) if tables is None else tables)
    pdf = np.empty(m, np.float32)
    f = np.empty((m, 3), np.float32)
    alb = np.empty((m, 3), np.float32)
    for s in range(0, m, CHUNK):
        c = min(CHUNK, m - s)
        g = padded(c)
        d_wi = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(wi_a[s:s + c]))
        d_wo = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(wo_a[s:s + c]))
        d_uv = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(uvs[s:s + c]))
        d_geo = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(geo[4 * s:4 * (s + c)]))
        p = np.empty(c, np.float32)
        ff = np.empty((c, 4), np.float32)
        aa = np.empty((c, 4), np.float32)
        bufs = [cl.Buffer(ctx, mf.WRITE_ONLY, a.nbytes) for a in (p, ff, aa)]
        k(queue, (g,), (LOCAL,), d_rows, d_tex, d_tables, d_wi, d_wo, d_uv, d_geo, np.uint32(c), *bufs)
        for a, b in zip((p, ff, aa), bufs):
            cl.enqueue_copy(queue, a, b)
        queue.finish()
        pdf[s:s + c] = p
        f[s:s + c] = ff[:, :3]
        alb[s:s + c] = aa[:, :3]
    return (pdf, f, alb) if with_albedo else (pdf, f)


# ------------------------------------------------------------------------------------------- warps
WARP_SRC = '#include "testing/warp_batch.cl"\n'  # kernels/testing/warp_batch.cl

WARPS = {"square": 0, "tent": 1, "disk": 2, "sphere": 3, "hemisphere": 4, "cosine_hemisphere": 5, "cone": 6,
         "triangle": 7, "beckmann": 8}


def warp_sample_batch(ctx, queue, warp: str, n: int, param: float = 0.0, seed: int = 0) -> np.ndarray:
    """n warped points (n,2) for 2-D warps or directions (n,3); `param`: cone cos_max or Beckmann alpha."""
    cl = _cl()
    kind = WARPS[warp]
    k = _kernel(ctx, "warp_sample_batch", WARP_SRC)
    out = np.empty((n, 4), np.float32)
    for s in range(0, n, CHUNK):
        m = min(CHUNK, n - s)
        buf = cl.Buffer(ctx, cl.mem_flags.WRITE_ONLY, m * 16)
        k(queue, (padded(m),), (LOCAL,), np.uint32(kind), np.float32(param), np.uint32(m), np.uint32(s),
          np.uint32(seed), buf)
        cl.enqueue_copy(queue, out[s:s + m], buf)
    queue.finish()
    return out[:, :2] if kind in (0, 1, 2, 7) else out[:, :3]


def warp_pdf_batch(ctx, queue, warp: str, points: np.ndarray, param: float = 0.0) -> np.ndarray:
    """The warp's density at points (m,2) or directions (m,3)."""
    cl = _cl()
    kind = WARPS[warp]
    k = _kernel(ctx, "warp_pdf_batch", WARP_SRC)
    p = np.asarray(points, np.float64)
    m = len(p)
    pts = np.zeros((m, 4), np.float32)
    pts[:, :p.shape[1]] = p
    out = np.empty(m, np.float32)
    for s in range(0, m, CHUNK):
        c = min(CHUNK, m - s)
        mf = cl.mem_flags
        d_in = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(pts[s:s + c]))
        d_out = cl.Buffer(ctx, mf.WRITE_ONLY, c * 4)
        k(queue, (padded(c),), (LOCAL,), np.uint32(kind), np.float32(param), np.uint32(c), d_in, d_out)
        cl.enqueue_copy(queue, out[s:s + c], d_out)
    queue.finish()
    return out
