/* Mitsuba 3's smooth plastic: a delta specular reflection (weight specular * F) over a diffuse base seen through
   the coating. Row: p.plastic = diffuse(_tex), specular(_tex) (colours or textures), eta = int/ext, fdr_int (the
   diffuse Fresnel reflectance from inside), spec_weight (Mitsuba's sampling bias), nonlinear.
     f_diffuse = d' (1 - F(cos_i)) (1 - F(cos_o)) / (pi eta^2),  d' = d / (1 - Fdr_int)  (nonlinear: d / (1 - d Fdr_int))
   eval and pdf hold the diffuse lobe only; a specular sample has MEASURE_DISCRETE. Front side only. */
#ifndef CLRENDER_BSDFS_PLASTIC_H
#define CLRENDER_BSDFS_PLASTIC_H
#include "common.h"
#include "../texture.h"
#include "warp.h"

/* Unpolarised Fresnel reflectance of light arriving from outside (cos > 0) on an eta = int/ext interface. */
INLINE float plastic_fresnel(float cos_i, float eta) {
    float cos_t;
    return fresnel_dielectric(cos_i, 1.0f, eta, &cos_t);
}

/* Probability of sampling the specular lobe (Mitsuba's rule: Fresnel times the reflectances' mean ratio). */
INLINE float plastic_prob_specular(float f_i, float s) {
    float ps = f_i * s, pd = (1.0f - f_i) * (1.0f - s);
    return ps + pd > 0.0f ? ps / (ps + pd) : 0.0f;
}

INLINE vec3 plastic_diffuse_colour(const BsdfQuery* q, __global const Bsdf* b) {
    vec3 d = param_color(q, b->p.plastic.diffuse, b->p.plastic.diffuse_tex);
    float fdr = b->p.plastic.fdr_int;
    return b->p.plastic.nonlinear ? vdiv(d, vsub(v3s(1.0f), vscale(d, fdr))) : vdivs(d, 1.0f - fdr);
}

INLINE vec3 plastic_eval(__global const Bsdf* b, const BsdfQuery* q) {
    if (q->wi.z <= 0.0f || q->wo.z <= 0.0f) return v3s(0.0f);
    float eta = b->p.plastic.eta;
    float t = (1.0f - plastic_fresnel(q->wi.z, eta)) * (1.0f - plastic_fresnel(q->wo.z, eta));
    return vscale(plastic_diffuse_colour(q, b), t * INV_PI / (eta * eta));
}

INLINE float plastic_pdf(__global const Bsdf* b, const BsdfQuery* q) {
    if (q->wi.z <= 0.0f || q->wo.z <= 0.0f) return 0.0f;
    float ps = plastic_prob_specular(plastic_fresnel(q->wi.z, b->p.plastic.eta), b->p.plastic.spec_weight);
    return (1.0f - ps) * q->wo.z * INV_PI;
}

INLINE vec3 plastic_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    q->eta = 1.0f;
    q->measure = MEASURE_SOLID_ANGLE;
    if (q->wi.z <= 0.0f) { q->wo = reflect_local(q->wi); return v3s(0.0f); }
    float f_i = plastic_fresnel(q->wi.z, b->p.plastic.eta);
    float ps = plastic_prob_specular(f_i, b->p.plastic.spec_weight);
    if (u.x < ps) {
        q->wo = reflect_local(q->wi);
        q->measure = MEASURE_DISCRETE;
        return vscale(param_color(q, b->p.plastic.specular, b->p.plastic.specular_tex), f_i / ps);
    }
    q->wo = square_to_cosine_hemisphere((float2)((u.x - ps) / (1.0f - ps), u.y));
    if (q->wo.z <= 0.0f) return v3s(0.0f);
    return bsdf_sample_weight(plastic_eval(b, q), q->wo.z, plastic_pdf(b, q));
}

INLINE vec3 plastic_albedo(__global const Bsdf* b, const BsdfQuery* q) {
    return param_color(q, b->p.plastic.diffuse, b->p.plastic.diffuse_tex);
}

#endif
