/* Mitsuba's thin dielectric: a sheet whose two parallel interfaces reflect light back and forth. With F the
   Fresnel reflectance of one interface (at |cos_i|, int_ior/ext_ior), the sheet reflects R = F + (1-F)^2 F/(1-F^2)
   (the sum over internal bounces) and lets the rest T = 1 - R through undeviated: wo = -wi, eta 1.
   Sampling picks reflection with probability R: weights specular_reflectance and specular_transmittance.
   Row: p.thindielectric = specular_reflectance, specular_transmittance (+ _tex), int_ior, ext_ior. Two-sided.
   A delta BSDF: eval and pdf are 0. */
#ifndef CLRENDER_BSDFS_THINDIELECTRIC_H
#define CLRENDER_BSDFS_THINDIELECTRIC_H
#include "common.h"
#include "../texture.h"

/* R, the sheet's reflectance at q->wi. */
INLINE float thindielectric_R(__global const Bsdf* b, const BsdfQuery* q) {
    float cos_t;
    float R = fresnel_dielectric(fabs(q->wi.z), b->p.thindielectric.ext_ior, b->p.thindielectric.int_ior, &cos_t);
    if (R < 1.0f) R += (1.0f - R) * (1.0f - R) * R / (1.0f - R * R);
    return R;
}

INLINE vec3 thindielectric_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    float R = thindielectric_R(b, q);
    q->measure = MEASURE_DISCRETE;
    q->eta = 1.0f;
    if (u.x < R) {
        q->wo = reflect_local(q->wi);
        return param_color(q, b->p.thindielectric.specular_reflectance,
                           b->p.thindielectric.specular_reflectance_tex);
    }
    q->wo = vneg(q->wi);
    return param_color(q, b->p.thindielectric.specular_transmittance, b->p.thindielectric.specular_transmittance_tex);
}

/* What passes straight through, T = 1 - R times specular_transmittance (Mitsuba's eval_null_transmission): volpath's
   shadow rays cross the sheet with it. */
INLINE vec3 thindielectric_null_transmission(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 t = param_color(q, b->p.thindielectric.specular_transmittance, b->p.thindielectric.specular_transmittance_tex);
    return vscale(t, 1.0f - thindielectric_R(b, q));
}

#endif
