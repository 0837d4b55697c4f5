/* Smooth dielectric interface. Row: p.dielectric = specular_reflectance, specular_transmittance (+ _tex:
   Mitsuba's factors on the two weights; 1 for Nori's plugin), int_ior, ext_ior.
   Sampling: reflect with probability F (unpolarised Fresnel, total internal reflection gives F = 1), refract
   otherwise. The side is the sign of cos(theta_i) = wi.z: wi.z > 0 is outside (extIOR), wi.z < 0 inside.
   Weights (radiance transport): reflection 1; refraction (eta_i / eta_t)^2 with eta_i the index on wi's side
   and eta_t on wo's side, so at normal incidence from outside the expected weight is
   F + (1-F) (extIOR/intIOR)^2. q->eta = eta_t / eta_i for refraction (intIOR/extIOR entering), 1 for
   reflection. A delta BSDF: eval and pdf are 0. */
#ifndef CLRENDER_BSDFS_DIELECTRIC_H
#define CLRENDER_BSDFS_DIELECTRIC_H
#include "common.h"
#include "../texture.h"

INLINE vec3 dielectric_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    float eta_int = b->p.dielectric.int_ior, eta_ext = b->p.dielectric.ext_ior;
    float cos_i = q->wi.z;
    float cos_t;
    float F = fresnel_dielectric(cos_i, eta_ext, eta_int, &cos_t);
    q->measure = MEASURE_DISCRETE;
    if (u.x < F) {
        q->wo = reflect_local(q->wi);
        q->eta = 1.0f;
        return param_color(q, b->p.dielectric.specular_reflectance, b->p.dielectric.specular_reflectance_tex);
    }
    bool outside = cos_i >= 0.0f;
    float eta_i = outside ? eta_ext : eta_int;
    float eta_t = outside ? eta_int : eta_ext;
    float r = eta_i / eta_t;
    /* Snell: the tangential part scales by eta_i/eta_t and flips (wi points away from the surface);
       the normal part goes to the other side. */
    q->wo = v3(-r * q->wi.x, -r * q->wi.y, outside ? -cos_t : cos_t);
    q->eta = eta_t / eta_i;
    vec3 t = param_color(q, b->p.dielectric.specular_transmittance, b->p.dielectric.specular_transmittance_tex);
    return vscale(t, r * r);
}

#endif
