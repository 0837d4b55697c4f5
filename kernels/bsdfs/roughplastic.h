/* Mitsuba 3's rough plastic: a microfacet specular lobe (Beckmann or GGX, dielectric Fresnel) over a diffuse base
   seen through the rough coating. Row: p.roughplastic = diffuse(_tex), specular(_tex), eta = int/ext, spec_weight,
   nonlinear, alpha, ggx, sample_visible, int_refl (R_int), trans[64] (T(mu) on uniform mu nodes; see
   clrender/bsdfs/roughplastic.py, which precomputes both).
     f = specular D F(wi.h) G1(wi,h) G1(wo,h) / (4 cos_i cos_o) + d' T(cos_i) T(cos_o) / (pi eta^2)
   Sampling: the specular lobe with probability (1-T(cos_i)) s / ((1-T) s + T (1-s)), else cosine-weighted. The
   specular normals are GGX visible normals (Heitz 2018) when sample_visible and ggx, otherwise D(m) cos(m). */
#ifndef CLRENDER_BSDFS_ROUGHPLASTIC_H
#define CLRENDER_BSDFS_ROUGHPLASTIC_H
#include "common.h"
#include "../texture.h"
#include "warp.h"

/* Microfacet distribution D(m) (isotropic), with Mitsuba's cut-off of negligible values. */
INLINE float rp_d(float3 m, float alpha, uint ggx) {
    float c = m.z;
    if (c <= 0.0f) return 0.0f;
    float c2 = c * c, a2 = alpha * alpha, xy2 = (m.x * m.x + m.y * m.y) / a2;
    float d;
    if (ggx) {
        float t = xy2 + c2;
        d = 1.0f / (M_PI_F_ * a2 * t * t);
    } else {
        float e = exp(-xy2 / c2);
        d = e > 0.0f ? e / (M_PI_F_ * a2 * c2 * c2) : 0.0f;
    }
    return d * c > 1e-20f ? d : 0.0f;
}

/* Smith's masking G1(v, m): exact for GGX, the rational fit for Beckmann; 0 when v sees the facet's back. */
INLINE float rp_g1(float3 v, float3 m, float alpha, uint ggx) {
    if (dot3(v, m) * v.z <= 0.0f) return 0.0f;
    float xy2 = alpha * alpha * (v.x * v.x + v.y * v.y);
    if (xy2 == 0.0f) return 1.0f;
    float tan2 = xy2 / (v.z * v.z);
    if (ggx) return 2.0f / (1.0f + sqrt(1.0f + tan2));
    float a = 1.0f / sqrt(tan2);
    return a >= 1.6f ? 1.0f : (3.535f * a + 2.181f * a * a) / (1.0f + 2.276f * a + 2.577f * a * a);
}

INLINE bool rp_visible(__global const Bsdf* b) { return b->p.roughplastic.sample_visible && b->p.roughplastic.ggx; }

/* A microfacet normal: GGX visible normals of wi, or D(m) cos(m) for both distributions. */
INLINE float3 rp_sample_normal(float3 wi, float alpha, uint ggx, bool visible, float2 u) {
    if (visible) {
        float3 vh = normalize3((float3)(alpha * wi.x, alpha * wi.y, wi.z));
        float len2 = vh.x * vh.x + vh.y * vh.y;
        float3 t1 = len2 > 0.0f ? (float3)(-vh.y, vh.x, 0.0f) / sqrt(len2) : (float3)(1.0f, 0.0f, 0.0f);
        float3 t2 = cross3(vh, t1);
        float r = sqrt(u.x);
        float2 sc = sin_cos(2.0f * M_PI_F_ * u.y);
        float p1 = r * sc.y, p2 = r * sc.x;
        float s = 0.5f * (1.0f + vh.z);
        p2 = (1.0f - s) * sqrt(maxf(0.0f, 1.0f - p1 * p1)) + s * p2;
        float3 nh = p1 * t1 + p2 * t2 + sqrt(maxf(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
        return normalize3((float3)(alpha * nh.x, alpha * nh.y, maxf(1e-6f, nh.z)));
    }
    float tan2 = ggx ? alpha * alpha * u.x / (1.0f - u.x) : -alpha * alpha * log(1.0f - u.x);
    float cos_t = 1.0f / sqrt(1.0f + tan2);
    float sin_t = safe_sqrt(1.0f - cos_t * cos_t);
    float2 sc = sin_cos(2.0f * M_PI_F_ * u.y);
    return (float3)(sin_t * sc.y, sin_t * sc.x, cos_t);
}

/* T(mu): linear interpolation of the precomputed table on uniform nodes of mu in [0, 1]. */
INLINE float rp_trans(__global const Bsdf* b, float mu) {
    float x = clamp(mu, 0.0f, 1.0f) * 63.0f;
    uint i = min((uint)x, 62u);
    float t = x - (float)i;
    return (1.0f - t) * b->p.roughplastic.trans[i] + t * b->p.roughplastic.trans[i + 1u];
}

INLINE float rp_prob_specular(__global const Bsdf* b, float t_i) {
    float s = b->p.roughplastic.spec_weight;
    float ps = (1.0f - t_i) * s, pd = t_i * (1.0f - s);
    return ps + pd > 0.0f ? ps / (ps + pd) : 0.0f;
}

INLINE float3 roughplastic_eval(__global const Bsdf* b, const BsdfQuery* q) {
    float3 wi = q->wi, wo = q->wo;
    if (wi.z <= 0.0f || wo.z <= 0.0f) return (float3)(0.0f);
    float alpha = b->p.roughplastic.alpha, eta = b->p.roughplastic.eta;
    uint ggx = b->p.roughplastic.ggx;
    float3 h = normalize3(wi + wo);
    float cos_t;
    float F = fresnel_dielectric(dot3(wi, h), 1.0f, eta, &cos_t);
    float spec = rp_d(h, alpha, ggx) * F * rp_g1(wi, h, alpha, ggx) * rp_g1(wo, h, alpha, ggx) / (4.0f * wi.z * wo.z);
    float3 d = param_color(q, b->p.roughplastic.diffuse, b->p.roughplastic.diffuse_tex);
    float r = b->p.roughplastic.int_refl;
    d = b->p.roughplastic.nonlinear ? d / ((float3)(1.0f) - d * r) : d / (1.0f - r);
    float diff = rp_trans(b, wi.z) * rp_trans(b, wo.z) * INV_PI / (eta * eta);
    return param_color(q, b->p.roughplastic.specular, b->p.roughplastic.specular_tex) * spec + d * diff;
}

INLINE float roughplastic_pdf(__global const Bsdf* b, const BsdfQuery* q) {
    float3 wi = q->wi, wo = q->wo;
    if (wi.z <= 0.0f || wo.z <= 0.0f) return 0.0f;
    float alpha = b->p.roughplastic.alpha;
    uint ggx = b->p.roughplastic.ggx;
    float ps = rp_prob_specular(b, rp_trans(b, wi.z));
    float3 h = normalize3(wi + wo);
    float spec;
    if (rp_visible(b)) spec = rp_d(h, alpha, ggx) * rp_g1(wi, h, alpha, ggx) / (4.0f * wi.z);
    else spec = rp_d(h, alpha, ggx) * h.z / (4.0f * dot3(wo, h));
    return ps * spec + (1.0f - ps) * wo.z * INV_PI;
}

INLINE float3 roughplastic_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    q->eta = 1.0f;
    q->measure = MEASURE_SOLID_ANGLE;
    if (q->wi.z <= 0.0f) { q->wo = reflect_local(q->wi); return (float3)(0.0f); }
    float ps = rp_prob_specular(b, rp_trans(b, q->wi.z));
    if (u.x < ps) {
        float3 m = rp_sample_normal(q->wi, b->p.roughplastic.alpha, b->p.roughplastic.ggx, rp_visible(b),
                                    (float2)(u.x / ps, u.y));
        q->wo = 2.0f * dot3(q->wi, m) * m - q->wi;
    } else {
        q->wo = square_to_cosine_hemisphere((float2)((u.x - ps) / (1.0f - ps), u.y));
    }
    if (q->wo.z <= 0.0f) return (float3)(0.0f);
    float pdf = roughplastic_pdf(b, q);
    if (!(pdf > 0.0f)) return (float3)(0.0f);
    return roughplastic_eval(b, q) * (q->wo.z / pdf);
}

INLINE float3 roughplastic_albedo(__global const Bsdf* b, const BsdfQuery* q) {
    return param_color(q, b->p.roughplastic.diffuse, b->p.roughplastic.diffuse_tex);
}

#endif
