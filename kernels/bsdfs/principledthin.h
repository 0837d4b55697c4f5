/* Mitsuba 3's thin principled BSDF, evaluated as Mitsuba 3.9 does (clrender/bsdfs/principledthin.py reads the
   parameters). A symmetric sheet: wi and wo are first turned so that wi is on the front. With st = spec_trans,
   dt = diff_trans / 2, wo' = wo mirrored to the front, h = normalize(wi + wo'), F the dielectric Fresnel term of eta
   at wi.h, D and G GGX's (principled_common.h; the transmission's roughness scaled by 0.65 eta - 0.35), SW(c) =
   (1 - c)^5:
     specular reflection    st lerp(F, Schlick(tint R0(eta)), spec_tint) D G / (4 cos_i cos_o)
     specular transmission  st base (1 - F) D' G' / (4 cos_i |cos_o|)      (wo on the other side, unbent)
     diffuse                (1 - st)(1 - dt) base / pi lerp((1 - SW_i/2)(1 - SW_o/2) + retro, HK, flatness)
     sheen                  (1 - st)(1 - dt) sheen SW(h.wo) lerp(1, base / lum, sheen_tint)
     diffuse transmission   (1 - st) dt base / pi
   Sampling picks the lobes in proportion to st r_sr / 2, st r_st / 2, (1 - st)(1 - dt) r_dr, (1 - st) dt r_dt
   (Mitsuba's; none depends on the sampled direction, so u.x picks the lobe and is reused), GGX visible normals for
   the specular lobes, cosine-weighted hemispheres for the diffuse ones. */
#ifndef CLRENDER_BSDFS_PRINCIPLEDTHIN_H
#define CLRENDER_BSDFS_PRINCIPLEDTHIN_H
#include "common.h"
#include "warp.h"
#include "distribution.h"
#include "principled_common.h"


/* the specular reflection's distribution, or (scaled) the specular transmission's */
INLINE MfDist pt_dist(__global const Bsdf* b, const BsdfQuery* q, bool scaled) {
    float r = PARAM_FLOAT(q, b->p.principledthin, roughness);
    if (scaled) r *= 0.65f * PARAM_FLOAT(q, b->p.principledthin, eta) - 0.35f;
    return pr_ggx(r, PARAM_FLOAT(q, b->p.principledthin, anisotropic));
}

/* Lobe probabilities (specular reflection, specular transmission, diffuse reflection, diffuse transmission). */
INLINE float4 pt_probs(__global const Bsdf* b, float st, float dt) {
    float4 p = (float4)(0.5f * st * b->p.principledthin.spec_refl_srate,
                        0.5f * st * b->p.principledthin.spec_trans_srate,
                        (1.0f - st) * (1.0f - dt) * b->p.principledthin.diff_refl_srate,
                        (1.0f - st) * dt * b->p.principledthin.diff_trans_srate);
    float t = p.x + p.y + p.z + p.w;
    return t > 0.0f ? p / t : (float4)(0.0f);
}

INLINE vec3 principledthin_eval(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo;
    if (wi.z == 0.0f) return v3s(0.0f);
    if (wi.z < 0.0f) { wi = vneg(wi); wo = vneg(wo); }
    float ci = wi.z, co = wo.z, aco = fabs(co);
    bool reflect = co > 0.0f, refract = co < 0.0f;
    if (!(reflect || refract)) return v3s(0.0f);
    float st = PARAM_FLOAT(q, b->p.principledthin, spec_trans);
    float dt = 0.5f * PARAM_FLOAT(q, b->p.principledthin, diff_trans);
    vec3 base = param_color(q, b->p.principledthin.base_color, b->p.principledthin.base_color_tex);
    vec3 h = normalize3(vadd(wi, v3(wo.x, wo.y, aco)));
    vec3 value = v3s(0.0f);
    if (st > 0.0f && pr_compatible(h, wi, wo, reflect)) {
        float eta = PARAM_FLOAT(q, b->p.principledthin, eta), wih = dot3(wi, h), cos_t;
        float F = fresnel_dielectric(wih, 1.0f, eta, &cos_t);
        MfDist d = pt_dist(b, q, !reflect);
        float DG = mf_d(d, h) * mf_g1(d, wi, h) * mf_g1(d, wo, h) / (4.0f * ci * aco);
        if (reflect) {
            float spec_tint = PARAM_FLOAT(q, b->p.principledthin, spec_tint);
            float lum = luminance(base);
            vec3 tint = lum > 0.0f ? vdivs(base, lum) : v3s(1.0f);
            float r0 = (eta - 1.0f) / (eta + 1.0f);
            vec3 Fs = pr_schlick(vscale(tint, r0 * r0), wih, eta);
            value = vmad(vlerp(v3s(F), Fs, spec_tint), st * DG, value);
        } else {
            value = vmad(base, st * (1.0f - F) * DG, value);
        }
    }
    if (reflect && st < 1.0f && dt < 1.0f) {
        float Fo = pr_sw(aco), Fi = pr_sw(ci), woh = dot3(h, wo);
        float roughness = PARAM_FLOAT(q, b->p.principledthin, roughness);
        float f_diff = (1.0f - 0.5f * Fi) * (1.0f - 0.5f * Fo);
        float rr = 2.0f * roughness * woh * woh;
        float f = f_diff + rr * (Fo + Fi + Fo * Fi * (rr - 1.0f));
        float flatness = PARAM_FLOAT(q, b->p.principledthin, flatness);
        if (flatness != 0.0f) {
            float fss90 = 0.5f * rr;
            float fss = (1.0f + (fss90 - 1.0f) * Fo) * (1.0f + (fss90 - 1.0f) * Fi);
            float f_ss = 1.25f * (fss * (1.0f / (aco + ci) - 0.5f) + 0.5f);
            f += flatness * (f_ss - f);
        }
        float w = (1.0f - st) * (1.0f - dt);
        value = vmad(base, w * INV_PI * f, value);
        float sheen = PARAM_FLOAT(q, b->p.principledthin, sheen);
        if (sheen != 0.0f) {
            float sheen_tint = PARAM_FLOAT(q, b->p.principledthin, sheen_tint);
            vec3 c = v3s(1.0f);
            if (sheen_tint != 0.0f) {
                float lum = luminance(base);
                vec3 tint = lum > 0.0f ? vdivs(base, lum) : v3s(1.0f);
                c = vlerp(c, tint, sheen_tint);
            }
            value = vmad(c, sheen * w * pr_sw(fabs(woh)), value);
        }
    }
    if (refract && st < 1.0f && dt > 0.0f) value = vmad(base, (1.0f - st) * dt * INV_PI, value);
    return value;
}

INLINE float principledthin_pdf(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo;
    if (wi.z == 0.0f) return 0.0f;
    if (wi.z < 0.0f) { wi = vneg(wi); wo = vneg(wo); }
    float co = wo.z;
    bool reflect = co > 0.0f, refract = co < 0.0f;
    float4 p = pt_probs(b, PARAM_FLOAT(q, b->p.principledthin, spec_trans),
                        0.5f * PARAM_FLOAT(q, b->p.principledthin, diff_trans));
    float pdf = 0.0f;
    if ((reflect && p.x > 0.0f) || (refract && p.y > 0.0f)) {
        vec3 wr = v3(wo.x, wo.y, fabs(co));
        vec3 h = normalize3(vadd(wi, wr));
        if (pr_compatible(h, wi, wo, reflect))
            pdf += (reflect ? p.x : p.y) * mf_pdf(pt_dist(b, q, !reflect), wi, h) / fabs(4.0f * dot3(wr, h));
    }
    if (reflect) pdf += p.z * co * INV_PI;
    if (refract) pdf -= p.w * co * INV_PI;
    return pdf;
}

INLINE vec3 principledthin_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    q->eta = 1.0f;
    q->measure = MEASURE_SOLID_ANGLE;
    q->wo = reflect_local(q->wi);
    float side = q->wi.z > 0.0f ? 1.0f : -1.0f;
    if (q->wi.z == 0.0f) return v3s(0.0f);
    vec3 wi = vscale(q->wi, side), wo;
    float4 p = pt_probs(b, PARAM_FLOAT(q, b->p.principledthin, spec_trans),
                        0.5f * PARAM_FLOAT(q, b->p.principledthin, diff_trans));
    float ux = u.x;
    /* the lobe, and u.x stretched back to [0, 1) within it */
    int lobe = 3;
    if (ux < p.x) lobe = 0;
    else if ((ux -= p.x) < p.y) lobe = 1;
    else if ((ux -= p.y) < p.z) lobe = 2;
    else ux -= p.z;
    float pl = lobe == 0 ? p.x : lobe == 1 ? p.y : lobe == 2 ? p.z : p.w;
    if (!(pl > 0.0f)) return v3s(0.0f);
    float2 v = (float2)(minf(ux / pl, 0.99999994f), u.y);
    if (lobe < 2) {
        vec3 m = mf_sample(pt_dist(b, q, lobe == 1), wi, v);
        wo = vsub(vscale(m, 2.0f * dot3(wi, m)), wi);
        if (lobe == 1) wo.z = -wo.z;
        if (!pr_compatible(m, wi, wo, lobe == 0) || !(lobe == 0 ? wo.z > 0.0f : wo.z < 0.0f)) return v3s(0.0f);
    } else {
        wo = square_to_cosine_hemisphere(v);
        if (lobe == 3) wo = vneg(wo);
        if (wo.z == 0.0f) return v3s(0.0f);
    }
    q->wo = vscale(wo, side);
    return bsdf_sample_weight(principledthin_eval(b, q), wo.z, principledthin_pdf(b, q));
}

INLINE vec3 principledthin_albedo(__global const Bsdf* b, const BsdfQuery* q) {
    return param_color(q, b->p.principledthin.base_color, b->p.principledthin.base_color_tex);
}

#endif
