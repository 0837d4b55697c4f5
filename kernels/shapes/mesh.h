/* Triangle meshes (clrender/shapes/trianglemesh.py): the surface at a hit and uniform-by-area sampling.

   A triangle is named by its leaf reference (Hit.prim: layout.py ENUMS PRIM_REF_*, clrender/accel/primitives.py
   leaf_refs), which says where its vertices are in the primitive table, their only copy on the device;
   tri_index holds its vertex indices at the same leaf-order position, for the per-vertex normals and uvs.
   Row: count = the mesh's triangle count; flags SHAPE_HAS_NORMALS (interpolated per-vertex normals shade) and
   SHAPE_HAS_UVS (per-vertex uvs; otherwise uv = the barycentrics (b1, b2)); SHAPE_NEEDS_UV (the BSDF reads uv or
   is anisotropic: the shading frame then follows dp/du, as Mitsuba's); emitting meshes: first = offset of
   their triangles' leaf references in `tri_refs`, cdf = offset of the triangle-area CDF in the `cdf` table
   (both in the mesh's triangle order), area = total area.
   Sampling picks a triangle by binary search in the CDF (probability area_i / A), rescales the sample and reuses
   it for uniform barycentrics, so the point has area density 1/A. */
#ifndef CLRENDER_SHAPES_MESH_H
#define CLRENDER_SHAPES_MESH_H
#include "common.h"

typedef struct {
    vec3 p0, p1, p2;
    uint i0, i1, i2;   /* vertex indices (rows of the per-vertex tables) */
} MeshTriangle;

/* The triangle with leaf reference `ref` (pos << PRIM_REF_POS_SHIFT | lane << 2 | (c - 1)): its block of c
   primitives starts at leaf-order position pos - lane, and row r of its lane is word 10 (pos - lane) + r c + lane
   of the primitive table (the block layout that bvh_isect_leaf reads, kernels/bvh_common.h). */
INLINE MeshTriangle mesh_triangle(const SceneData* sd, uint ref) {
    uint pos = ref >> PRIM_REF_POS_SHIFT, lane = (ref >> 2) & 3u, c = (ref & 3u) + 1u;
    __global const float* q = (__global const float*)sd->prims + (10u * (pos - lane) + lane);
    MeshTriangle t;
    t.p0 = v3(q[0], q[c], q[2u * c]);
    t.p1 = v3(q[3u * c], q[4u * c], q[5u * c]);
    t.p2 = v3(q[6u * c], q[7u * c], q[8u * c]);
    __global const uint* idx = sd->tri_index + 3u * pos;
    t.i0 = idx[0]; t.i1 = idx[1]; t.i2 = idx[2];
    return t;
}

/* A component of a stored normal: 16-bit signed fixed point (bits h, two's complement) over 32767 (trianglemesh.py
   fixed_normals), decoded with integer arithmetic only (no short conversion of out-of-range values). */
INLINE float mesh_snorm16(uint h) {
    return (float)((int)h - (int)((h & 0x8000u) << 1)) * (1.0f / 32767.0f);
}

/* p0 w0 + p1 w1 + p2 w2: vertex values interpolated with barycentric weights, rounded as that expression in float3
   was (p1 w1 on its own, the other two products fused into the sums). */
INLINE vec3 mesh_bary(vec3 p0, vec3 p1, vec3 p2, float w0, float w1, float w2) {
    return vmad(p2, w2, vmad(p0, w0, vscale(p1, w1)));
}

/* Per-vertex normal i (3 16-bit components a row: the table has no padding). */
INLINE vec3 mesh_normal(const SceneData* sd, uint i) {
    __global const ushort* n = sd->normals + 3u * i;
    return v3(mesh_snorm16(n[0]), mesh_snorm16(n[1]), mesh_snorm16(n[2]));
}

/* The shading normal at barycentrics (b0, b1, b2) of triangle t: interpolated vertex normals, or ng. */
INLINE vec3 mesh_shading_normal(const SceneData* sd, __global const Shape* s, const MeshTriangle* t, float b0,
                                float b1, float b2, vec3 ng) {
    if (!(s->flags & SHAPE_HAS_NORMALS)) return ng;
    vec3 n = mesh_bary(mesh_normal(sd, t->i0), mesh_normal(sd, t->i1), mesh_normal(sd, t->i2), b0, b1, b2);
    float l2 = dot3(n, n);
    return l2 > 0.0f ? vscale(n, 1.0f / sqrt(l2)) : ng;
}

/* Component c (0: u, 1: v) of the uv interpolated with weights b0, b1, b2 at vertices i0, i1, i2: read and summed as
   floats, since float2 loads and arithmetic are vector-typed instructions, which keep a stage kernel's work-item
   loop scalar (kernels/math.h) */
INLINE float mesh_uv(const SceneData* sd, uint c, uint i0, uint i1, uint i2, float b0, float b1, float b2) {
    __global const float* uv = (__global const float*)sd->uvs + c;
    return uv[2u * i0] * b0 + uv[2u * i1] * b1 + uv[2u * i2] * b2;
}

/* Mitsuba's dp/du and dp/dv of triangle t: from its uvs, or where it has none (or they are degenerate) its first
   and second edges. */
INLINE vec3 mesh_dpduv(const SceneData* sd, __global const Shape* s, const MeshTriangle* t, vec3* dpdv) {
    vec3 dp0 = vsub(t->p1, t->p0), dp1 = vsub(t->p2, t->p0);
    *dpdv = dp1;
    if (!(s->flags & SHAPE_HAS_UVS)) return dp0;
    __global const float* uv = (__global const float*)sd->uvs;
    float u0 = uv[2u * t->i0], v0 = uv[2u * t->i0 + 1u];
    float du0 = uv[2u * t->i1] - u0, dv0 = uv[2u * t->i1 + 1u] - v0;
    float du1 = uv[2u * t->i2] - u0, dv1 = uv[2u * t->i2 + 1u] - v0;
    float det = du0 * dv1 - dv0 * du1;
    if (det == 0.0f) return dp0;
    float inv = 1.0f / det;
    *dpdv = vscale(vmad(dp1, du0, vscale(dp0, -du1)), inv);
    return vscale(vmad(dp0, dv1, vscale(dp1, -dv0)), inv);
}

INLINE vec3 mesh_dpdu(const SceneData* sd, __global const Shape* s, const MeshTriangle* t) {
    vec3 dpdv;
    return mesh_dpduv(sd, s, t, &dpdv);
}

INLINE bool mesh_surface(const SceneData* sd, __global const Shape* s, const Ray* r, const Hit* h,
                         Intersection* its) {
    MeshTriangle tri = mesh_triangle(sd, h->prim);
    float b0 = 1.0f - h->u - h->v;
    vec3 p0 = tri.p0, p1 = tri.p1, p2 = tri.p2;
    its->p = mesh_bary(p0, p1, p2, b0, h->u, h->v);
    vec3 c = cross3(vsub(p1, p0), vsub(p2, p0));
    float a2 = len3(c);                          /* twice the area */
    vec3 ng = vscale(c, 1.0f / a2);
    its->ng = ng;
    float off = SPAWN_OFFSET * maxf(max3(vabs(p0)), maxf(max3(vabs(p1)), max3(vabs(p2))));
    its->off = off;
    /* The spawn base: p moved into the triangle until it is `off` or more from every edge (barycentric
       off * |edge| / a2 for the vertex across that edge), so that near a concave edge the origin is not on
       or behind the neighbouring wall's plane, where p's rounding error alone can put it. */
    float k = off / a2;
    float w0 = maxf(b0, k * len3(vsub(p2, p1))), w1 = maxf(h->u, k * len3(vsub(p0, p2))),
          w2 = maxf(h->v, k * len3(vsub(p1, p0)));
    float ws = w0 + w1 + w2;
    its->po = ws > 0.0f && ws < INFINITY ? vscale(mesh_bary(p0, p1, p2, w0, w1, w2), 1.0f / ws) : its->p;
    vec3 n = mesh_shading_normal(sd, s, &tri, b0, h->u, h->v, ng);
    bool has_uv = (s->flags & SHAPE_HAS_UVS) != 0u;
    its->uv = (float2)(has_uv ? mesh_uv(sd, 0u, tri.i0, tri.i1, tri.i2, b0, h->u, h->v) : h->u,
                       has_uv ? mesh_uv(sd, 1u, tri.i0, tri.i1, tri.i2, b0, h->u, h->v) : h->v);
    its->sh = (s->flags & SHAPE_NEEDS_UV) ? frame_from_tangent(n, mesh_dpdu(sd, s, &tri)) : frame_from_normal(n);
#ifdef CLR_SURFACE_DERIVATIVES
    bool uv = (s->flags & SHAPE_NEEDS_UV) != 0u;
    its->dpdu = uv ? mesh_dpduv(sd, s, &tri, &its->dpdv) : v3s(0.0f);
    if (!uv) its->dpdv = v3s(0.0f);
#endif
    its->tri = h->prim;
    return true;
}

INLINE float mesh_sample(const SceneData* sd, __global const Shape* s, vec3 ref, float2 u, ShapeSample* ss) {
    __global const float* cdf = sd->cdf + s->cdf;
    uint i = shape_cdf_search(cdf, s->count, u.x);
    float lo = i > 0u ? cdf[i - 1u] : 0.0f, hi = cdf[i];
    float ux = hi > lo ? (u.x - lo) / (hi - lo) : 0.5f;
    ux = clampf(ux, 0.0f, 0x1.fffffep-1f);
    MeshTriangle tri = mesh_triangle(sd, sd->tri_refs[s->first + i]);
    vec3 p0 = tri.p0, p1 = tri.p1, p2 = tri.p2;
    float2 b = square_to_uniform_triangle((float2)(ux, u.y));
    float b0 = 1.0f - b.x - b.y;
    vec3 p = mesh_bary(p0, p1, p2, b0, b.x, b.y);
    vec3 ng = normalize3(cross3(vsub(p1, p0), vsub(p2, p0)));
    vec3 n = mesh_shading_normal(sd, s, &tri, b0, b.x, b.y, ng);
    float pdf = shape_point_sample(ss, ref, p, n, ng, 1.0f / s->area);
    /* the uv mesh_surface gives at this point (textured emission) */
    bool has_uv = (s->flags & SHAPE_HAS_UVS) != 0u;
    ss->uv = (float2)(has_uv ? mesh_uv(sd, 0u, tri.i0, tri.i1, tri.i2, b0, b.x, b.y) : b.x,
                      has_uv ? mesh_uv(sd, 1u, tri.i0, tri.i1, tri.i2, b0, b.x, b.y) : b.y);
    return pdf;
}

/* The density of the point p (hit along wi) that mesh_sample would give: per point, so a direction that meets
   the mesh several times has the sum of these as its density (the shadow ray settles which point is seen). */
INLINE float mesh_pdf(const SceneData* sd, __global const Shape* s, vec3 ref, vec3 p, vec3 ng, vec3 wi) {
    return shape_solid_angle_pdf(1.0f / s->area, ref, p, ng, wi);
}

#endif
