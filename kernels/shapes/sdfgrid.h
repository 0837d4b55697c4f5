/* SDF grids (clrender/shapes/sdfgrid.py): the surface at a hit, as Mitsuba 3.9.1's sdfgrid computes it. The BVH
   finds the hit (kernels/bvh_common.h bvh_isect_voxel: the zero of the trilinear interpolation of the grid's values
   in one voxel); this gives its normals.

   Row: first = offset of the values in sd->grid_data (x fastest); p.sdfgrid.to_object[0..2] = rows of the affine
   map world -> the grid's unit cube [0, 1]^3; .res = (xres, yres, zres, 1: smooth shading normals, 0: analytic);
   .extent = the grid's size in the world (the scale of the offset of rays leaving the surface).
   The grid's values sit at the corners of its (res - 1)^3 voxels, value i at i / (res - 1) of the cube.

   Geometric normal: the gradient of the voxel's interpolation at the hit (Mitsuba's `analytic`), taken to the
   world as a normal (by to_object's transpose). Shading normal with `smooth` (Mitsuba's default, after
   Hansson-Söderlund et al., JCGT 11(3) 2022): the normalised gradients of the eight voxels about the grid point
   nearest the hit, each evaluated at the hit, blended trilinearly; voxels with a negative index count as absent.
   No uv (Mitsuba's sdfgrid has none), no area: it cannot emit, and samples nothing. */
#ifndef CLRENDER_SHAPES_SDFGRID_H
#define CLRENDER_SHAPES_SDFGRID_H
#include "common.h"
#include "../grid.h"

/* The grid's interpolated value at grid coordinates g (value i at g = i), indices clamped into the grid, as
   Mitsuba's linear, clamped Texture3f lookup. */
INLINE float sdfgrid_value(const SceneData* sd, __global const Shape* s, vec3 g) {
    uint4 r = s->p.sdfgrid.res;
    return grid_trilinear(sd->grid_data + s->first, (uint4)(r.x, r.y, r.z, 1u), g, 2u).x;
}

/* The gradient in the grid's unit cube of voxel (vx, vy, vz)'s interpolation at grid coordinates g: along each
   axis, the difference of the values on the voxel's two faces across it (at g's other coordinates). */
INLINE vec3 sdfgrid_voxel_grad(const SceneData* sd, __global const Shape* s, vec3 g, int vx, int vy, int vz) {
    uint4 r = s->p.sdfgrid.res;
    float x0 = (float)vx, y0 = (float)vy, z0 = (float)vz;
    return v3((sdfgrid_value(sd, s, v3(x0 + 1.0f, g.y, g.z)) - sdfgrid_value(sd, s, v3(x0, g.y, g.z))) * (float)(r.x - 1u),
              (sdfgrid_value(sd, s, v3(g.x, y0 + 1.0f, g.z)) - sdfgrid_value(sd, s, v3(g.x, y0, g.z))) * (float)(r.y - 1u),
              (sdfgrid_value(sd, s, v3(g.x, g.y, z0 + 1.0f)) - sdfgrid_value(sd, s, v3(g.x, g.y, z0))) * (float)(r.z - 1u));
}

INLINE vec3 sdfgrid_unit(vec3 v) {
    float l2 = dot3(v, v);
    return l2 > 0.0f ? vscale(v, 1.0f / sqrt(l2)) : v3s(0.0f);
}

/* Hansson-Söderlund et al.'s smooth normal (in the unit cube) at grid coordinates g. */
INLINE vec3 sdfgrid_smooth(const SceneData* sd, __global const Shape* s, vec3 g) {
    int ex = (int)rint(g.x), ey = (int)rint(g.y), ez = (int)rint(g.z);   /* the nearest grid point */
    float w[3] = {g.x - (float)ex + 0.5f, g.y - (float)ey + 0.5f, g.z - (float)ez + 0.5f};
    int lo[3] = {ex - 1, ey - 1, ez - 1};
    /* an axis whose lower voxels are all absent weighs only the upper ones (a negative index: the grid's edge) */
    bool absent_low[3], absent_high[3];
    for (int k = 0; k < 3; ++k) absent_low[k] = absent_high[k] = true;
    vec3 n[8];
    for (int c = 0; c < 8; ++c) {
        int b[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
        int vx = lo[0] + b[0], vy = lo[1] + b[1], vz = lo[2] + b[2];
        bool present = vx >= 0 && vy >= 0 && vz >= 0;
        n[c] = present ? sdfgrid_unit(sdfgrid_voxel_grad(sd, s, g, vx, vy, vz)) : v3s(0.0f);
        for (int k = 0; k < 3; ++k) {
            if (!present) continue;
            if (b[k]) absent_high[k] = false; else absent_low[k] = false;
        }
    }
    for (int k = 0; k < 3; ++k) {
        if (absent_low[k]) w[k] = 1.0f;
        if (absent_high[k]) w[k] = 0.0f;
    }
    vec3 acc = v3s(0.0f);
    for (int c = 0; c < 8; ++c) {
        float wc = ((c & 1) ? w[0] : 1.0f - w[0]) * ((c & 2) ? w[1] : 1.0f - w[1]) * ((c & 4) ? w[2] : 1.0f - w[2]);
        acc = vmad(n[c], wc, acc);
    }
    return acc;
}

/* A normal in the unit cube taken to the world: by the transpose of to_object's linear part. */
INLINE vec3 sdfgrid_normal_to_world(__global const Shape* s, vec3 n) {
    float4 a = s->p.sdfgrid.to_object[0], b = s->p.sdfgrid.to_object[1], c = s->p.sdfgrid.to_object[2];
    return sdfgrid_unit(v3(a.x * n.x + b.x * n.y + c.x * n.z, a.y * n.x + b.y * n.y + c.y * n.z,
                           a.z * n.x + b.z * n.y + c.z * n.z));
}

INLINE bool sdfgrid_surface(const SceneData* sd, __global const Shape* s, const Ray* r, const Hit* h,
                            Intersection* its) {
    vec3 p = vmad(r->d, h->t, r->o);
    uint4 res = s->p.sdfgrid.res;
    float4 m0 = s->p.sdfgrid.to_object[0], m1 = s->p.sdfgrid.to_object[1], m2 = s->p.sdfgrid.to_object[2];
    vec3 g = v3((m0.x * p.x + m0.y * p.y + m0.z * p.z + m0.w) * (float)(res.x - 1u),
                (m1.x * p.x + m1.y * p.y + m1.z * p.z + m1.w) * (float)(res.y - 1u),
                (m2.x * p.x + m2.y * p.y + m2.z * p.z + m2.w) * (float)(res.z - 1u));
    /* the voxel holding the hit (within the grid: a hit on its outer face belongs to the last voxel) */
    int vx = clamp(floor_index(g.x), 0, (int)res.x - 2), vy = clamp(floor_index(g.y), 0, (int)res.y - 2);
    int vz = clamp(floor_index(g.z), 0, (int)res.z - 2);
    vec3 ng = sdfgrid_normal_to_world(s, sdfgrid_voxel_grad(sd, s, g, vx, vy, vz));
    if (is_black(ng)) ng = vneg(normalize3(r->d));     /* a flat spot of the field: face the ray */
    vec3 ns = res.w ? sdfgrid_normal_to_world(s, sdfgrid_smooth(sd, s, g)) : ng;
    if (is_black(ns)) ns = ng;
    its->p = p;
    its->po = p;
    its->off = 4.0f * SPAWN_OFFSET * (max3(vabs(p)) + s->p.sdfgrid.extent);
    its->ng = ng;
    its->sh = frame_from_normal(ns);
    its->uv = (float2)(0.0f);
#ifdef CLR_SURFACE_DERIVATIVES
    its->dpdu = its->dpdv = v3s(0.0f);
#endif
    its->tri = NONE;
    return true;
}

/* An SDF grid has no area (Mitsuba's neither): it is never an emitter, so these are never reached. */
INLINE float sdfgrid_sample(const SceneData* sd, __global const Shape* s, vec3 ref, float2 u, ShapeSample* ss) {
    return 0.0f;
}

INLINE float sdfgrid_pdf(const SceneData* sd, __global const Shape* s, vec3 ref, vec3 p, vec3 ng, vec3 wi) {
    return 0.0f;
}

#endif
