/* Mitsuba's rough dielectric (Walter et al. 2007): a Beckmann or GGX microfacet interface between int_ior (below
   the surface) and ext_ior (above). With eta = eta_t / eta_i (wo's side over wi's side, as q->eta),
   m the microfacet normal (upper hemisphere) and F the dielectric Fresnel term at wi.m:
     reflection (wi, wo on one side):  m ~ wi + wo,
         f = R F D G / (4 |cos_i| |cos_o|),                        dwo/dm: 1 / (4 |wo.m|)
     refraction:                        m ~ wi + eta wo,
         f = T (1-F) D G |wi.m| |wo.m| / (|cos_i| |cos_o| (wi.m + eta wo.m)^2)
                                                                    dwo/dm: eta^2 |wo.m| / (wi.m + eta wo.m)^2
   (radiance transport: the eta^2 of the importance form cancels against the (eta_i/eta_t)^2 radiance scaling),
   G = G1(wi,m) G1(wo,m), R/T = specular_reflectance/_transmittance. Sampling draws m for wi flipped above the
   surface (distribution.h), then reflects with probability F and refracts otherwise:
     pdf = p_m(m) (F or 1-F) dwo/dm.
   Row: p.roughdielectric = specular_reflectance, specular_transmittance (+ _tex), int_ior, ext_ior, alpha_u,
   alpha_v (+ _tex), distribution, sample_visible. */
#ifndef CLRENDER_BSDFS_ROUGHDIELECTRIC_H
#define CLRENDER_BSDFS_ROUGHDIELECTRIC_H
#include "common.h"
#include "distribution.h"

INLINE MfDist roughdielectric_dist(__global const Bsdf* b, const BsdfQuery* q) {
    return mf_make(q, b->p.roughdielectric.distribution, b->p.roughdielectric.alpha_u,
                   b->p.roughdielectric.alpha_u_tex, b->p.roughdielectric.alpha_v, b->p.roughdielectric.alpha_v_tex,
                   b->p.roughdielectric.sample_visible);
}

/* The microfacet normal that takes wi to wo and the event's eta; false where no microfacet does (or the
   geometry is inconsistent: wi or wo on the back of m relative to their own side). */
INLINE bool roughdielectric_half(__global const Bsdf* b, vec3 wi, vec3 wo, vec3* m, float* eta,
                                 bool* reflect) {
    float ci = wi.z, co = wo.z;
    if (ci == 0.0f || co == 0.0f) return false;
    float ein = b->p.roughdielectric.int_ior, eex = b->p.roughdielectric.ext_ior;
    *reflect = ci * co > 0.0f;
    *eta = *reflect ? 1.0f : (ci > 0.0f ? ein / eex : eex / ein);
    vec3 h = vadd(wi, vscale(wo, *eta));
    float l = dot3(h, h);
    if (!(l > 0.0f)) return false;
    h = vscale(h, 1.0f / sqrt(l));
    if (h.z < 0.0f) h = vneg(h);
    *m = h;
    return dot3(wi, h) * ci > 0.0f && dot3(wo, h) * co > 0.0f;
}

INLINE vec3 roughdielectric_eval(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo, m;
    float eta;
    bool reflect;
    if (!roughdielectric_half(b, wi, wo, &m, &eta, &reflect)) return v3s(0.0f);
    MfDist d = roughdielectric_dist(b, q);
    float DG = mf_d(d, m) * mf_g1(d, wi, m) * mf_g1(d, wo, m);
    if (!(DG > 0.0f)) return v3s(0.0f);
    float wim = dot3(wi, m), wom = dot3(wo, m), cos_t;
    float F = fresnel_dielectric(wim, b->p.roughdielectric.ext_ior, b->p.roughdielectric.int_ior, &cos_t);
    float cc = fabs(wi.z * wo.z);
    if (reflect)
        return vscale(param_color(q, b->p.roughdielectric.specular_reflectance,
                                  b->p.roughdielectric.specular_reflectance_tex), F * DG / (4.0f * cc));
    float den = wim + eta * wom;
    float v = (1.0f - F) * DG * fabs(wim * wom) / (cc * den * den);
    return vscale(param_color(q, b->p.roughdielectric.specular_transmittance,
                              b->p.roughdielectric.specular_transmittance_tex), v);
}

INLINE float roughdielectric_pdf(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo, m;
    float eta;
    bool reflect;
    if (!roughdielectric_half(b, wi, wo, &m, &eta, &reflect)) return 0.0f;
    MfDist d = roughdielectric_dist(b, q);
    vec3 wi_up = wi.z > 0.0f ? wi : vneg(wi);
    float pm = mf_pdf(d, wi_up, m);
    float wim = dot3(wi, m), wom = dot3(wo, m), cos_t;
    float F = fresnel_dielectric(wim, b->p.roughdielectric.ext_ior, b->p.roughdielectric.int_ior, &cos_t);
    if (reflect) return pm * F / (4.0f * fabs(wom));
    float den = wim + eta * wom;
    return pm * (1.0f - F) * eta * eta * fabs(wom) / (den * den);
}

INLINE vec3 roughdielectric_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    vec3 wi = q->wi;
    q->measure = MEASURE_SOLID_ANGLE;
    q->eta = 1.0f;
    q->wo = v3(0.0f, 0.0f, 1.0f);
    if (wi.z == 0.0f) return v3s(0.0f);
    MfDist d = roughdielectric_dist(b, q);
    vec3 wi_up = wi.z > 0.0f ? wi : vneg(wi);
    vec3 m = mf_sample(d, wi_up, u);
    float wim = dot3(wi, m), cos_t;
    float ein = b->p.roughdielectric.int_ior, eex = b->p.roughdielectric.ext_ior;
    float F = fresnel_dielectric(wim, eex, ein, &cos_t);
    bool reflect = mf_extra_uniform(u) < F;
    if (reflect) {
        q->wo = vsub(vscale(m, 2.0f * wim), wi);
    } else {
        /* wi.m > 0: wi is on the ext side of the microfacet, refraction enters the object */
        float ei = wim > 0.0f ? eex : ein, et = wim > 0.0f ? ein : eex;
        q->wo = normalize3(refract_about(wi, m, ei / et, cos_t));
        q->eta = et / ei;
    }
    /* an event that ends on the wrong side of the macro-surface is lost (as in Mitsuba): the pdf below is the
       density of the samples that survive, so it integrates to less than 1 at grazing angles */
    if (reflect ? !(q->wo.z * wi.z > 0.0f) : !(q->wo.z * wi.z < 0.0f)) return v3s(0.0f);
    return bsdf_sample_weight(roughdielectric_eval(b, q), q->wo.z, roughdielectric_pdf(b, q));
}

#endif
