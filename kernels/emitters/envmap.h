/* Mitsuba 3's environment map (clrender/emitters/envmap.py gives the conventions): bilinear radiance over a
   latitude-longitude image, importance sampled by a piecewise-constant 2-D distribution over its cells and, within
   a cell, by the bilinear patch of its corners' luminances.

   Emitter row: flags EMITTER_INFINITE; p.envmap.dims = (first texel row in the textures table, W, H, offset of the
   CDFs in `cdf`: H-1 marginal values, then H-1 conditional CDFs of W values each); inv[0..2].xyz = rows of the
   world-to-local rotation, inv[0].w = scale. Texels: H rows of W+1 float4 (the last column repeats the first). */
#ifndef CLRENDER_EMITTERS_ENVMAP_H
#define CLRENDER_EMITTERS_ENVMAP_H
#include "common.h"
#include "../shapes/common.h"   /* shape_cdf_search */

INLINE vec3 envmap_to_local(__global const Emitter* em, vec3 d) {
    return v3(dot3(vrow(em->p.envmap.inv[0]), d), dot3(vrow(em->p.envmap.inv[1]), d),
              dot3(vrow(em->p.envmap.inv[2]), d));
}

/* Grid coordinates of a local unit direction: x in [0, W) (shifted by half a texel), y in [0, H-1]. */
INLINE float2 envmap_grid(__global const Emitter* em, vec3 v) {
    uint4 dims = em->p.envmap.dims;
    float u = atan2(v.x, -v.z) * INV_TWOPI - 0.5f / (float)dims.y;
    u -= floor(u);
    float t = acos(clampf(v.y, -1.0f, 1.0f)) * INV_PI;
    return (float2)(u * (float)dims.y, t * (float)(dims.z - 1u));
}

/* Probability of cell (ix, iy) and the row's conditional CDF. */
INLINE float envmap_cell_pmf(const SceneData* sd, __global const Emitter* em, uint ix, uint iy) {
    uint4 dims = em->p.envmap.dims;
    __global const float* marg = sd->cdf + dims.w;
    __global const float* cond = marg + (dims.z - 1u) + iy * dims.y;
    float pr = marg[iy] - (iy > 0u ? marg[iy - 1u] : 0.0f);
    float pc = cond[ix] - (ix > 0u ? cond[ix - 1u] : 0.0f);
    return pr * pc;
}

/* Luminances (at least 0) of cell (ix, iy)'s corners: top left, top right, bottom left, bottom right. */
INLINE float4 envmap_corners(const SceneData* sd, __global const Emitter* em, uint ix, uint iy) {
    uint4 dims = em->p.envmap.dims;
    __global const float4* px = (__global const float4*)(sd->textures + dims.x);
    uint w1 = dims.y + 1u, i = iy * w1 + ix;
    return (float4)(fmax(luminance(vrow(px[i])), 0.0f), fmax(luminance(vrow(px[i + 1u])), 0.0f),
                    fmax(luminance(vrow(px[i + w1])), 0.0f), fmax(luminance(vrow(px[i + w1 + 1u])), 0.0f));
}

/* Within a cell a point is drawn with density proportional to the bilinear patch of its corner luminances, as the
   radiance varies there (uniform in the cell, a lone bright texel's four cells gave 4 (1 - x)(1 - y) / pdf: a
   relative spread of 0.88 where Mitsuba's bilinear warp has almost none). This is that density over the uniform
   one; 1 in a black cell (drawn uniformly). */
INLINE float envmap_in_cell(float4 c, float fx, float fy) {
    float mean = 0.25f * (c.x + c.y + c.z + c.w);
    if (!(mean > 0.0f)) return 1.0f;
    return (mad(c.y - c.x, fx, c.x) * (1.0f - fy) + mad(c.w - c.z, fx, c.z) * fy) / mean;
}

/* The inverse CDF on [0, 1) of the density proportional to a (1 - x) + b x (a, b >= 0), as u (a + b) / (a + r)
   with r = sqrt(a^2 (1 - u) + b^2 u), the form without cancellation when a and b are close. */
INLINE float envmap_linear_warp(float a, float b, float u) {
    float r = sqrt(mad(a * a, 1.0f - u, b * b * u));
    return a + r > 0.0f ? clampf(u * (a + b) / (a + r), 0.0f, 0x1.fffffep-1f) : u;
}

/* Solid-angle density of local direction v (unit). */
INLINE float envmap_local_pdf(const SceneData* sd, __global const Emitter* em, vec3 v) {
    uint4 dims = em->p.envmap.dims;
    float sin_t = sqrt(v.x * v.x + v.z * v.z);
    if (!(sin_t > 0.0f)) return 0.0f;
    float2 g = envmap_grid(em, v);
    uint ix = min((uint)g.x, dims.y - 1u), iy = min((uint)g.y, dims.z - 2u);
    float in_cell = envmap_in_cell(envmap_corners(sd, em, ix, iy), g.x - (float)ix, g.y - (float)iy);
    float pdf_uv = envmap_cell_pmf(sd, em, ix, iy) * in_cell * (float)dims.y * (float)(dims.z - 1u);
    return pdf_uv / (2.0f * M_PI_F_ * M_PI_F_ * sin_t);
}

INLINE vec3 envmap_lookup(const SceneData* sd, __global const Emitter* em, vec3 v) {
    uint4 dims = em->p.envmap.dims;
    __global const float4* px = (__global const float4*)(sd->textures + dims.x);
    float2 g = envmap_grid(em, v);
    uint ix = min((uint)g.x, dims.y - 1u), iy = min((uint)g.y, dims.z - 2u);
    float fx = g.x - (float)ix, fy = g.y - (float)iy;
    uint w1 = dims.y + 1u, i = iy * w1 + ix;
    vec3 top = vmad(vrow(px[i]), 1.0f - fx, vscale(vrow(px[i + 1u]), fx));
    vec3 bot = vmad(vrow(px[i + w1]), 1.0f - fx, vscale(vrow(px[i + w1 + 1u]), fx));
    vec3 mid = vmad(top, 1.0f - fy, vscale(bot, fy));
    return vscale(mid, em->p.envmap.inv[0].w);
}

INLINE vec3 envmap_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    uint4 dims = em->p.envmap.dims;
    uint rows = dims.z - 1u;
    __global const float* marg = sd->cdf + dims.w;
    uint iy = shape_cdf_search(marg, rows, u.y);
    float lo = iy > 0u ? marg[iy - 1u] : 0.0f, hi = marg[iy];
    float fy = hi > lo ? clampf((u.y - lo) / (hi - lo), 0.0f, 0x1.fffffep-1f) : 0.5f;
    __global const float* cond = marg + rows + iy * dims.y;
    uint ix = shape_cdf_search(cond, dims.y, u.x);
    lo = ix > 0u ? cond[ix - 1u] : 0.0f;
    hi = cond[ix];
    float fx = hi > lo ? clampf((u.x - lo) / (hi - lo), 0.0f, 0x1.fffffep-1f) : 0.5f;
    float4 c = envmap_corners(sd, em, ix, iy);
    fy = envmap_linear_warp(c.x + c.y, c.z + c.w, fy);
    fx = envmap_linear_warp(mad(c.z - c.x, fy, c.x), mad(c.w - c.y, fy, c.y), fx);
    float uu = ((float)ix + fx) / (float)dims.y + 0.5f / (float)dims.y;
    float vv = ((float)iy + fy) / (float)rows;
    float2 sp = sin_cos(M_PI_F_ * vv), sc = sin_cos(2.0f * M_PI_F_ * uu);
    vec3 v = v3(sc.x * sp.x, sp.y, -sc.y * sp.x);
    vec3 r0 = vrow(em->p.envmap.inv[0]), r1 = vrow(em->p.envmap.inv[1]), r2 = vrow(em->p.envmap.inv[2]);
    vec3 wi = normalize3(vmad(r2, v.z, vmad(r0, v.x, vscale(r1, v.y))));
    q->wi = wi;
    q->p = vmad(wi, emitter_far(sd, q->ref), q->ref);
    q->n = vneg(wi);
    q->ng = vneg(wi);
    q->dist = INFINITY;
    /* the density of the direction as pdf() will see it, so that sample and pdf agree exactly */
    float pdf = envmap_local_pdf(sd, em, envmap_to_local(em, wi));
    q->pdf = pdf;
    return pdf > 0.0f ? vscale(envmap_lookup(sd, em, envmap_to_local(em, wi)), 1.0f / pdf) : v3s(0.0f);
}

INLINE float envmap_pdf(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return envmap_local_pdf(sd, em, envmap_to_local(em, q->wi));
}

INLINE vec3 envmap_eval(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return envmap_lookup(sd, em, envmap_to_local(em, q->wi));
}

#endif
