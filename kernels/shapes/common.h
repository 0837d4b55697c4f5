/* What the shape plugins share (kernels/shapes/<name>.h): the record of a point sampled on a shape, and the
   conversion of an area density to a solid-angle density. */
#ifndef CLRENDER_SHAPES_COMMON_H
#define CLRENDER_SHAPES_COMMON_H
#include "../math.h"
#include "../frame.h"
#include "../warp.h"

/* A point sampled on a shape as seen from a reference point: where it is, its shading normal n and geometric
   normal ng (the measure's), and the direction/distance from the reference point. The `_sample` functions return
   the solid-angle density of wi at the reference point (0: no usable sample). */
typedef struct {
    vec3 p, n, ng, wi;
    float dist;
    float2 uv;   /* the surface's uv at p, as at a hit (spheres compute it only with SHAPE_NEEDS_UV; else 0) */
} ShapeSample;

/* Solid-angle density at ref of a point p with area density `inv_area` (dist^2 / (area |cos at p|)); 0 when
   degenerate (grazing, coincident). cos is taken against the geometric normal: the true change of measure. */
INLINE float shape_solid_angle_pdf(float inv_area, vec3 ref, vec3 p, vec3 ng, vec3 wi) {
    vec3 d = vsub(p, ref);
    float d2 = dot3(d, d);
    float c = fabs(dot3(ng, wi));
    if (c <= 0.0f || d2 <= 0.0f) return 0.0f;
    return inv_area * d2 / c;
}

/* Complete a sample at p (normals n, ng) drawn with area density inv_area; returns its solid-angle density. */
INLINE float shape_point_sample(ShapeSample* ss, vec3 ref, vec3 p, vec3 n, vec3 ng, float inv_area) {
    vec3 d = vsub(p, ref);
    float l = len3(d);
    ss->wi = l > 0.0f ? vscale(d, 1.0f / l) : ng;
    ss->p = p;
    ss->n = n;
    ss->ng = ng;
    ss->dist = l;
    ss->uv = (float2)(0.0f);
    return shape_solid_angle_pdf(inv_area, ref, p, ng, ss->wi);
}

/* First index i in cdf[0..count) with cdf[i] > u (the CDF ends with 1, u < 1). */
INLINE uint shape_cdf_search(__global const float* cdf, uint count, float u) {
#if defined(CLR_SEARCH_STEPS) && defined(CLR_WAVEFRONT_STAGES)
    return min(table_count_le(cdf, count, u), count - 1u);
#else
    uint lo = 0u, hi = count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) >> 1;
        if (cdf[mid] > u) hi = mid; else lo = mid + 1u;
    }
    return lo;
#endif
}

#endif
