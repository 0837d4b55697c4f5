/* Mitsuba's rough conductor: a Beckmann or GGX microfacet BRDF (anisotropic alpha_u, alpha_v) with the conductor
   Fresnel term of eta + i k:
     f   = R F(wi.h) D(h) G1(wi,h) G1(wo,h) / (4 cos_i cos_o),   h = normalize(wi + wo),  R = specular_reflectance
     pdf = p_m(h) / (4 wo.h),   p_m the density of distribution.h (visible normals when sample_visible)
   Row: p.roughconductor = eta, k, specular_reflectance (+ _tex), alpha_u, alpha_v (+ _tex: float textures read
   their first channel), distribution (MF_BECKMANN / MF_GGX), sample_visible. One-sided, like Mitsuba's. */
#ifndef CLRENDER_BSDFS_ROUGHCONDUCTOR_H
#define CLRENDER_BSDFS_ROUGHCONDUCTOR_H
#include "common.h"
#include "distribution.h"

INLINE MfDist roughconductor_dist(__global const Bsdf* b, const BsdfQuery* q) {
    return mf_make(q, b->p.roughconductor.distribution, b->p.roughconductor.alpha_u,
                   b->p.roughconductor.alpha_u_tex, b->p.roughconductor.alpha_v, b->p.roughconductor.alpha_v_tex,
                   b->p.roughconductor.sample_visible);
}

INLINE vec3 roughconductor_eval(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo;
    if (wi.z <= 0.0f || wo.z <= 0.0f) return v3s(0.0f);
    MfDist d = roughconductor_dist(b, q);
    vec3 h = normalize3(vadd(wi, wo));
    float s = mf_d(d, h) * mf_g1(d, wi, h) * mf_g1(d, wo, h) / (4.0f * wi.z * wo.z);
    if (!(s > 0.0f)) return v3s(0.0f);
    vec3 F = fresnel_conductor(dot3(wi, h), vrow(b->p.roughconductor.eta), vrow(b->p.roughconductor.k));
    vec3 r = param_color(q, b->p.roughconductor.specular_reflectance, b->p.roughconductor.specular_reflectance_tex);
    return vmul(vscale(F, s), r);
}

INLINE float roughconductor_pdf(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo;
    if (wi.z <= 0.0f || wo.z <= 0.0f) return 0.0f;
    MfDist d = roughconductor_dist(b, q);
    vec3 h = normalize3(vadd(wi, wo));
    float ho = dot3(h, wo);
    if (ho <= 0.0f) return 0.0f;
    /* dwo = 4 (wo.h) dh: the Jacobian of reflecting wi about h */
    return mf_pdf(d, wi, h) / (4.0f * ho);
}

INLINE vec3 roughconductor_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    q->measure = MEASURE_SOLID_ANGLE;
    q->eta = 1.0f;
    q->wo = v3(0.0f, 0.0f, 1.0f);
    if (q->wi.z <= 0.0f) return v3s(0.0f);
    MfDist d = roughconductor_dist(b, q);
    vec3 h = mf_sample(d, q->wi, u);
    q->wo = vsub(vscale(h, 2.0f * dot3(q->wi, h)), q->wi);
    if (q->wo.z <= 0.0f) return v3s(0.0f);
    return bsdf_sample_weight(roughconductor_eval(b, q), q->wo.z, roughconductor_pdf(b, q));
}

#endif
