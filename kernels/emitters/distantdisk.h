/* Distant disk (a sun, or with thetaA = 180 a uniform environment): radiance L from every direction within
   theta_A of an axis, nothing elsewhere.

   Emitter row: flags EMITTER_INFINITE; p.distantdisk: radiance.xyz = L; frame[0..2].xyz = the world images of
   local x, y, z (z = the axis: the direction from the scene TOWARD the light); cos_max = cos theta_A,
   one_minus_cos = 1 - cos theta_A (formed on the host in double precision), pdf = the cone pdf
   1 / (2 pi (1 - cos theta_A)).
   sample: uniform in the cone, returns L / pdf, dist = INFINITY. */
#ifndef CLRENDER_EMITTERS_DISTANTDISK_H
#define CLRENDER_EMITTERS_DISTANTDISK_H
#include "common.h"

/* 1 - cos(angle between wi and the axis) >= 0, accurate for small angles (via |wi x axis|). */
INLINE bool distantdisk_inside(__global const Emitter* em, vec3 wi) {
    vec3 z = vrow(em->p.distantdisk.frame[2]);
    float c = dot3(wi, z);
    float omc_max = em->p.distantdisk.one_minus_cos;
    if (omc_max >= 2.0f) return true;
    if (c <= 0.0f) return c >= em->p.distantdisk.cos_max;
    vec3 x = cross3(wi, z);
    float s2 = dot3(x, x);
    /* 1 - cos = sin^2 / (1 + cos) */
    return s2 / (1.0f + c) <= omc_max;
}

INLINE vec3 distantdisk_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    float omc_max = em->p.distantdisk.one_minus_cos;
    float omc = u.x * omc_max;
    float cos_t = 1.0f - omc;
    float sin_t = safe_sqrt(omc * (2.0f - omc));
    float phi = 2.0f * M_PI_F_ * u.y;
    float2 sc = sin_cos(phi);
    vec3 fx = vrow(em->p.distantdisk.frame[0]), fy = vrow(em->p.distantdisk.frame[1]);
    vec3 fz = vrow(em->p.distantdisk.frame[2]);
    vec3 wi = vmad(fz, cos_t, vmad(fx, sin_t * sc.y, vscale(fy, sin_t * sc.x)));
    wi = normalize3(wi);
    q->wi = wi;
    q->p = vmad(wi, emitter_far(sd, q->ref), q->ref);
    q->n = vneg(wi);
    q->ng = vneg(wi);
    q->dist = INFINITY;
    q->pdf = em->p.distantdisk.pdf;
    return vscale(vrow(em->p.distantdisk.radiance), 1.0f / q->pdf);
}

INLINE float distantdisk_pdf(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return distantdisk_inside(em, q->wi) ? em->p.distantdisk.pdf : 0.0f;
}

INLINE vec3 distantdisk_eval(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return distantdisk_inside(em, q->wi) ? vrow(em->p.distantdisk.radiance) : v3s(0.0f);
}

#endif
