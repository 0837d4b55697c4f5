/* Area light on a mesh or an analytic sphere: radiance L on the side the shading normal faces.

   Emitter row: flags EMITTER_SURFACE; shape = the emitting shape; p.area.radiance.xyz = L, p.area.area = total
   area A; cdf_offset/count = the shape's normalised cumulative triangle-area CDF in emitter_cdf (spheres: count 1).

   Meshes: a triangle is picked by binary search in the CDF (probability area_i / A), the sample is rescaled
   and reused for uniform barycentrics, so the point has area density 1/A; in solid angle at ref that is
   pdf = dist^2 / (A |cos theta_l|), theta_l against the triangle's geometric normal.
   Spheres (centre c, radius r) seen from outside (|ref - c| > r): uniform directions in the cone of
   half-angle asin(r / |ref - c|) about c - ref, pdf = 1 / (2 pi (1 - cos theta_max)); the point is the near
   intersection of that direction with the sphere. From inside: uniform by area like a mesh. */
#ifndef CLRENDER_EMITTERS_AREA_H
#define CLRENDER_EMITTERS_AREA_H
#include "common.h"

/* First index i in cdf[0..count) with cdf[i] > u (the CDF ends with 1, u < 1). */
INLINE uint area_cdf_search(__global const float* cdf, uint count, float u) {
    uint lo = 0u, hi = count - 1u;
    while (lo < hi) {
        uint mid = (lo + hi) >> 1;
        if (cdf[mid] > u) hi = mid; else lo = mid + 1u;
    }
    return lo;
}

/* 1 - cos(theta_max) of the cone a sphere subtends, stable for small spheres: sin^2 / (1 + cos). */
INLINE float area_sphere_one_minus_cos(float r2, float d2) {
    float sin2 = r2 / d2;
    float cosm = safe_sqrt(1.0f - sin2);
    return sin2 / (1.0f + cosm);
}

/* Convert the area density 1/A of a point to solid angle at ref; 0 when degenerate (grazing, coincident). */
INLINE float area_solid_angle_pdf(float inv_area, float3 ref, float3 p, float3 ng, float3 wi) {
    float3 d = p - ref;
    float d2 = dot3(d, d);
    float c = fabs(dot3(ng, wi));
    if (c <= 0.0f || d2 <= 0.0f) return 0.0f;
    return inv_area * d2 / c;
}

/* Complete the query for a point p (shading normal n, geometric normal ng) drawn with area density 1/A;
   returns L/pdf, or 0 when p faces away from ref (one-sided) or the conversion is degenerate. */
INLINE float3 area_point_sample(__global const Emitter* em, EmitterQuery* q, float3 p, float3 n, float3 ng,
                                float area) {
    float3 d = p - q->ref;
    float l = len3(d);
    q->wi = l > 0.0f ? d * (1.0f / l) : ng;
    q->p = p;
    q->n = n;
    q->ng = ng;
    q->dist = l;
    q->pdf = area_solid_angle_pdf(1.0f / area, q->ref, p, ng, q->wi);
    return (q->pdf > 0.0f && dot3(n, q->wi) < 0.0f) ? em->p.area.radiance.xyz * (1.0f / q->pdf) : (float3)(0.0f);
}

INLINE float3 area_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    Shape sh = sd->shapes[em->shape];
    float area = em->p.area.area;
    float3 ref = q->ref;
    if (sh.flags & SHAPE_SPHERE) {
        float4 s = sd->spheres[sh.first];
        float3 oc = s.xyz - ref;
        float d2 = dot3(oc, oc), r2 = s.w * s.w;
        if (d2 > r2) {
            /* Cone sampling about the axis toward the centre. 1 - cos theta is formed directly (no
               cancellation for distant spheres). */
            float d = sqrt(d2);
            float3 axis = oc * (1.0f / d);
            float omc_max = area_sphere_one_minus_cos(r2, d2);
            float omc = u.x * omc_max;
            float cos_t = 1.0f - omc;
            float sin2 = omc * (2.0f - omc);
            float sin_t = safe_sqrt(sin2);
            float phi = 2.0f * M_PI_F_ * u.y;
            Frame f = frame_from_normal(axis);
            float2 sc = sin_cos(phi);
            float3 wi = normalize3(to_world(&f, (float3)(sin_t * sc.y, sin_t * sc.x, cos_t)));
            /* near intersection: t = d cos - sqrt(r^2 - d^2 sin^2) */
            float t = d * cos_t - safe_sqrt(r2 - d2 * sin2);
            float3 n = normalize3(ref + wi * t - s.xyz);
            float3 p = s.xyz + n * s.w;
            q->wi = wi;
            q->p = p;
            q->n = n;
            q->ng = n;
            q->dist = len3(p - ref);
            q->pdf = 1.0f / (2.0f * M_PI_F_ * omc_max);
            return dot3(n, wi) < 0.0f ? em->p.area.radiance.xyz * (1.0f / q->pdf) : (float3)(0.0f);
        }
        /* inside: uniform on the sphere */
        float3 n = square_to_uniform_sphere(u);
        float3 p = s.xyz + n * s.w;
        return area_point_sample(em, q, p, n, n, area);
    }
    /* mesh: pick a triangle by area, rescale u.x for reuse */
    __global const float* cdf = sd->emitter_cdf + em->cdf_offset;
    uint i = area_cdf_search(cdf, em->count, u.x);
    float lo = i > 0u ? cdf[i - 1u] : 0.0f, hi = cdf[i];
    float ux = hi > lo ? (u.x - lo) / (hi - lo) : 0.5f;
    ux = clampf(ux, 0.0f, 0x1.fffffep-1f);
    uint4 idx = sd->tri_index[sh.first + i];
    float3 p0 = sd->positions[idx.x].xyz, p1 = sd->positions[idx.y].xyz, p2 = sd->positions[idx.z].xyz;
    float2 b = square_to_uniform_triangle((float2)(ux, u.y));
    float b0 = 1.0f - b.x - b.y;
    float3 p = p0 * b0 + p1 * b.x + p2 * b.y;
    float3 ng = normalize3(cross3(p1 - p0, p2 - p0));
    float3 n = ng;
    if (sh.flags & SHAPE_HAS_NORMALS) {
        float3 m = sd->normals[idx.x].xyz * b0 + sd->normals[idx.y].xyz * b.x + sd->normals[idx.z].xyz * b.y;
        float l2 = dot3(m, m);
        if (l2 > 0.0f) n = m * (1.0f / sqrt(l2));
    }
    return area_point_sample(em, q, p, n, ng, area);
}

INLINE float area_pdf(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    Shape sh = sd->shapes[em->shape];
    if (sh.flags & SHAPE_SPHERE) {
        float4 s = sd->spheres[sh.first];
        float3 oc = s.xyz - q->ref;
        float d2 = dot3(oc, oc), r2 = s.w * s.w;
        if (d2 > r2) {
            /* the direction must meet the sphere: in front, closest approach within r (relative slack for
               rays that hit exactly at the silhouette) */
            float3 c = cross3(q->wi, oc);
            if (dot3(q->wi, oc) <= 0.0f || dot3(c, c) > r2 * 1.0001f) return 0.0f;
            return 1.0f / (2.0f * M_PI_F_ * area_sphere_one_minus_cos(r2, d2));
        }
    }
    return area_solid_angle_pdf(1.0f / em->p.area.area, q->ref, q->p, q->ng, q->wi);
}

INLINE float3 area_eval(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return dot3(q->n, q->wi) < 0.0f ? em->p.area.radiance.xyz : (float3)(0.0f);
}

#endif
