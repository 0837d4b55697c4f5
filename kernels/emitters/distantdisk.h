/* Distant disk (a sun, or with thetaA = 180 a uniform environment): radiance L from every direction within
   theta_A of an axis, nothing elsewhere.

   Emitter row: type EMITTER_DISTANTDISK; radiance.xyz = L; params[0..2].xyz = the world images of local
   x, y, z (z = the axis: the direction from the scene TOWARD the light); params[3].x = cos theta_A,
   params[3].y = 1 - cos theta_A (formed on the host in double precision), params[3].z = the cone pdf
   1 / (2 pi (1 - cos theta_A)).
   sample: uniform in the cone, returns L / pdf, dist = INFINITY. */
#ifndef CLRENDER_EMITTERS_DISTANTDISK_H
#define CLRENDER_EMITTERS_DISTANTDISK_H
#ifndef CLRENDER_EMITTER_H
#error "include emitter.h, not emitters/distantdisk.h"
#endif

/* 1 - cos(angle between wi and the axis) >= 0, accurate for small angles (via |wi x axis|). */
INLINE bool distantdisk_inside(__global const Emitter* em, float3 wi) {
    float3 z = em->params[2].xyz;
    float c = dot3(wi, z);
    float omc_max = em->params[3].y;
    if (omc_max >= 2.0f) return true;
    if (c <= 0.0f) return c >= em->params[3].x;
    float3 x = cross3(wi, z);
    float s2 = dot3(x, x);
    /* 1 - cos = sin^2 / (1 + cos) */
    return s2 / (1.0f + c) <= omc_max;
}

INLINE float3 distantdisk_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    float omc_max = em->params[3].y;
    float omc = u.x * omc_max;
    float cos_t = 1.0f - omc;
    float sin_t = safe_sqrt(omc * (2.0f - omc));
    float phi = 2.0f * M_PI_F_ * u.y;
    float2 sc = sin_cos(phi);
    float3 wi = em->params[0].xyz * (sin_t * sc.y) + em->params[1].xyz * (sin_t * sc.x)
              + em->params[2].xyz * cos_t;
    wi = normalize3(wi);
    q->wi = wi;
    q->p = q->ref + wi * emitter_far(sd, q->ref);
    q->n = -wi;
    q->ng = -wi;
    q->dist = INFINITY;
    q->pdf = em->params[3].z;
    return em->radiance.xyz * (1.0f / q->pdf);
}

INLINE float distantdisk_pdf(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return distantdisk_inside(em, q->wi) ? em->params[3].z : 0.0f;
}

INLINE float3 distantdisk_eval(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return distantdisk_inside(em, q->wi) ? em->radiance.xyz : (float3)(0.0f);
}

#endif
