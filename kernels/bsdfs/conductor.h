/* Mitsuba's smooth conductor: a mirror whose reflectance is the conductor Fresnel term of the complex index
   eta + i k, times specular_reflectance. Row: p.conductor = eta, k, specular_reflectance (+ _tex).
   One-sided (wi below the surface: nothing). A delta BSDF: eval and pdf are 0. */
#ifndef CLRENDER_BSDFS_CONDUCTOR_H
#define CLRENDER_BSDFS_CONDUCTOR_H
#include "common.h"
#include "distribution.h"

INLINE vec3 conductor_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    q->measure = MEASURE_DISCRETE;
    q->eta = 1.0f;
    q->wo = reflect_local(q->wi);
    if (q->wi.z <= 0.0f) return v3s(0.0f);
    vec3 F = fresnel_conductor(q->wi.z, vrow(b->p.conductor.eta), vrow(b->p.conductor.k));
    return vmul(F, param_color(q, b->p.conductor.specular_reflectance, b->p.conductor.specular_reflectance_tex));
}

#endif
