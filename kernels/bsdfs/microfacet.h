/* Nori's microfacet BRDF: a diffuse base plus a Beckmann specular lobe with dielectric Fresnel.
   Row: p.microfacet = kd, kd_tex (a colour or a texture: see texture.h), alpha, int_ior, ext_ior,
   ks = 1 - max(kd) (set by the host).
     f   = kd/pi + ks D(h) F(h.wi) G1(wi,h) G1(wo,h) / (4 cos_i cos_o),   h = normalize(wi + wo)
     pdf = ks D(h) cos(theta_h) / (4 |h.wo|) + (1 - ks) cos_o / pi
   D is beckmann_d (warp.h, the standard D with cos^4), F the Fresnel term extIOR -> intIOR, G1 the rational
   Smith-Beckmann fit. Only reflection: both wi and wo must be above the surface. */
#ifndef CLRENDER_BSDFS_MICROFACET_H
#define CLRENDER_BSDFS_MICROFACET_H
#include "common.h"
#include "../texture.h"
#include "warp.h"

INLINE float microfacet_g1(vec3 v, vec3 h, float alpha) {
    if (dot3(v, h) / v.z <= 0.0f) return 0.0f;
    float sin2 = maxf(0.0f, 1.0f - v.z * v.z);
    if (sin2 <= 0.0f) return 1.0f;
    float tan_t = sqrt(sin2) / v.z;
    float bb = 1.0f / (alpha * tan_t);
    if (bb >= 1.6f) return 1.0f;
    return (3.535f * bb + 2.181f * bb * bb) / (1.0f + 2.276f * bb + 2.577f * bb * bb);
}

INLINE vec3 microfacet_eval(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo;
    if (wi.z <= 0.0f || wo.z <= 0.0f) return v3s(0.0f);
    float alpha = b->p.microfacet.alpha, eta_int = b->p.microfacet.int_ior, eta_ext = b->p.microfacet.ext_ior;
    float ks = b->p.microfacet.ks;
    vec3 h = normalize3(vadd(wi, wo));
    float cos_t;
    float F = fresnel_dielectric(dot3(h, wi), eta_ext, eta_int, &cos_t);
    float spec = beckmann_d(h, alpha) * F * microfacet_g1(wi, h, alpha) * microfacet_g1(wo, h, alpha)
                 / (4.0f * wi.z * wo.z);
    return vadds(vscale(param_color(q, b->p.microfacet.kd, b->p.microfacet.kd_tex), INV_PI), ks * spec);
}

INLINE float microfacet_pdf(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo;
    if (wi.z <= 0.0f || wo.z <= 0.0f) return 0.0f;
    float alpha = b->p.microfacet.alpha, ks = b->p.microfacet.ks;
    vec3 h = normalize3(vadd(wi, wo));
    /* dwo = 4 |h.wo| dh: the Jacobian of reflecting wi about h */
    float spec = square_to_beckmann_pdf(h, alpha) / (4.0f * fabs(dot3(h, wo)));
    return ks * spec + (1.0f - ks) * wo.z * INV_PI;
}

INLINE vec3 microfacet_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    float alpha = b->p.microfacet.alpha, ks = b->p.microfacet.ks;
    q->measure = MEASURE_SOLID_ANGLE;
    q->eta = 1.0f;
    if (u.x < ks) {
        u.x = u.x / ks;   /* re-use the sample dimension: uniform again on [0,1) */
        vec3 h = square_to_beckmann(u, alpha);
        q->wo = vsub(vscale(h, 2.0f * dot3(q->wi, h)), q->wi);
    } else {
        u.x = (u.x - ks) / (1.0f - ks);
        q->wo = square_to_cosine_hemisphere(u);
    }
    if (q->wi.z <= 0.0f || q->wo.z <= 0.0f) return v3s(0.0f);
    return bsdf_sample_weight(microfacet_eval(b, q), q->wo.z, microfacet_pdf(b, q));
}

INLINE vec3 microfacet_albedo(__global const Bsdf* b, const BsdfQuery* q) {
    return param_color(q, b->p.microfacet.kd, b->p.microfacet.kd_tex);
}

#endif
