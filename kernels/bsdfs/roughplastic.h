/* Mitsuba 3's rough plastic: a microfacet specular lobe (Beckmann or GGX, dielectric Fresnel) over a diffuse base
   seen through the rough coating. Row: p.roughplastic = diffuse(_tex), specular(_tex), eta = int/ext, spec_weight,
   nonlinear, alpha, ggx, sample_visible, int_refl (R_int), table (T(mu) on BSDF_TABLE_SIZE uniform mu nodes: a
   row of the scene's bsdf_tables, q->tables; clrender/bsdfs/roughplastic.py precomputes both).
     f = specular D F(wi.h) G1(wi,h) G1(wo,h) / (4 cos_i cos_o) + d' T(cos_i) T(cos_o) / (pi eta^2)
   Sampling: the specular lobe with probability (1-T(cos_i)) s / ((1-T) s + T (1-s)), else cosine-weighted. The
   specular normals are GGX visible normals (Heitz 2018) when sample_visible and ggx, otherwise D(m) cos(m). */
#ifndef CLRENDER_BSDFS_ROUGHPLASTIC_H
#define CLRENDER_BSDFS_ROUGHPLASTIC_H
#include "common.h"
#include "../texture.h"
#include "warp.h"
#include "distribution.h"

INLINE bool rp_visible(__global const Bsdf* b) { return b->p.roughplastic.sample_visible && b->p.roughplastic.ggx; }

/* The isotropic specular lobe's distribution (D and G1 of distribution.h, as Mitsuba's rough plastic uses them). */
INLINE MfDist rp_dist(__global const Bsdf* b) {
    MfDist d;
    d.type = b->p.roughplastic.ggx ? MF_GGX : MF_BECKMANN;
    d.ax = d.ay = b->p.roughplastic.alpha;
    d.visible = rp_visible(b);
    return d;
}

/* A microfacet normal: GGX visible normals of wi (distribution.h's sampler), else D(m) cos(m) for both
   distributions, drawn here because mf_sample maps u to the opposite azimuth (the same density, other images). */
INLINE vec3 rp_sample_normal(MfDist d, vec3 wi, float2 u) {
    if (d.visible) return mf_sample(d, wi, u);
    float a2 = d.ax * d.ax;
    float tan2 = d.type == MF_GGX ? a2 * u.x / (1.0f - u.x) : -a2 * log(1.0f - u.x);
    float cos_t = 1.0f / sqrt(1.0f + tan2);
    float sin_t = safe_sqrt(1.0f - cos_t * cos_t);
    float2 sc = sin_cos(2.0f * M_PI_F_ * u.y);
    return v3(sin_t * sc.y, sin_t * sc.x, cos_t);
}

/* T(mu): linear interpolation of the precomputed table on uniform nodes of mu in [0, 1]. */
INLINE float rp_trans(__global const Bsdf* b, const BsdfQuery* q, float mu) {
    __global const float* trans = q->tables[b->p.roughplastic.table].values;
    float x = clamp(mu, 0.0f, 1.0f) * (float)(BSDF_TABLE_SIZE - 1u);
    uint i = min((uint)x, BSDF_TABLE_SIZE - 2u);
    float t = x - (float)i;
    return (1.0f - t) * trans[i] + t * trans[i + 1u];
}

INLINE float rp_prob_specular(__global const Bsdf* b, float t_i) {
    float s = b->p.roughplastic.spec_weight;
    float ps = (1.0f - t_i) * s, pd = t_i * (1.0f - s);
    return ps + pd > 0.0f ? ps / (ps + pd) : 0.0f;
}

INLINE vec3 roughplastic_eval(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo;
    if (wi.z <= 0.0f || wo.z <= 0.0f) return v3s(0.0f);
    float eta = b->p.roughplastic.eta;
    MfDist dist = rp_dist(b);
    vec3 h = normalize3(vadd(wi, wo));
    float cos_t;
    float F = fresnel_dielectric(dot3(wi, h), 1.0f, eta, &cos_t);
    float spec = mf_d(dist, h) * F * mf_g1(dist, wi, h) * mf_g1(dist, wo, h) / (4.0f * wi.z * wo.z);
    vec3 d = param_color(q, b->p.roughplastic.diffuse, b->p.roughplastic.diffuse_tex);
    float r = b->p.roughplastic.int_refl;
    d = b->p.roughplastic.nonlinear ? vdiv(d, vsub(v3s(1.0f), vscale(d, r))) : vdivs(d, 1.0f - r);
    float diff = rp_trans(b, q, wi.z) * rp_trans(b, q, wo.z) * INV_PI / (eta * eta);
    vec3 s = param_color(q, b->p.roughplastic.specular, b->p.roughplastic.specular_tex);
    return vadd(vscale(s, spec), vscale(d, diff));
}

INLINE float roughplastic_pdf(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo;
    if (wi.z <= 0.0f || wo.z <= 0.0f) return 0.0f;
    float ps = rp_prob_specular(b, rp_trans(b, q, wi.z));
    vec3 h = normalize3(vadd(wi, wo));
    /* dwo = 4 (wo.h) dh: the Jacobian of reflecting wi about h */
    float spec = mf_pdf(rp_dist(b), wi, h) / (4.0f * dot3(wo, h));
    return ps * spec + (1.0f - ps) * wo.z * INV_PI;
}

INLINE vec3 roughplastic_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    q->eta = 1.0f;
    q->measure = MEASURE_SOLID_ANGLE;
    if (q->wi.z <= 0.0f) { q->wo = reflect_local(q->wi); return v3s(0.0f); }
    float ps = rp_prob_specular(b, rp_trans(b, q, q->wi.z));
    if (u.x < ps) {
        vec3 m = rp_sample_normal(rp_dist(b), q->wi, (float2)(u.x / ps, u.y));
        q->wo = vsub(vscale(m, 2.0f * dot3(q->wi, m)), q->wi);
    } else {
        q->wo = square_to_cosine_hemisphere((float2)((u.x - ps) / (1.0f - ps), u.y));
    }
    if (q->wo.z <= 0.0f) return v3s(0.0f);
    return bsdf_sample_weight(roughplastic_eval(b, q), q->wo.z, roughplastic_pdf(b, q));
}

INLINE vec3 roughplastic_albedo(__global const Bsdf* b, const BsdfQuery* q) {
    return param_color(q, b->p.roughplastic.diffuse, b->p.roughplastic.diffuse_tex);
}

#endif
