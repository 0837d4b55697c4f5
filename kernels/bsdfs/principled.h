/* Mitsuba 3's principled BSDF, evaluated as Mitsuba 3.9 does (clrender/bsdfs/principled.py reads the parameters).
   With brdf = (1 - metallic)(1 - spec_trans), bsdf = (1 - metallic) spec_trans, eta_p = eta from the front side
   (1/eta from the back), h the half vector (wi + wo for reflection, wi + eta_p wo for refraction) turned to the
   upper hemisphere, F the dielectric Fresnel term at wi.h, D and G GGX's (alpha = max(1e-3, roughness^2), stretched
   by sqrt(1 - 0.9 anisotropic)), SW(c) = (1 - c)^5:
     main specular   Fp D G / (4 |cos_i| |cos_o|), Fp = (1-metallic)(1-spec_tint) F + metallic Schlick(base)
                     + (1-metallic) spec_tint Schlick(tint R0(eta)) on the front; bsdf F on the back
     transmission    sqrt(base) bsdf |(1-F) D G (wi.h)(wo.h) / (cos_i (wi.h + eta_p wo.h)^2)| / |cos_o|
                     (radiance form: Mitsuba's eta_p^2 cancels against the 1/eta_p^2 of radiance transport)
     clearcoat       0.25 clearcoat Schlick(0.04) GTR1(h) G_0.25(wi) G_0.25(wo)   (front only; no 1/(4 cos cos),
                     as in Mitsuba)
     diffuse         brdf base / pi lerp((1 - SW_i/2)(1 - SW_o/2) + retro, HK, flatness)          (front only)
     sheen           sheen (1 - metallic) SW(h.wo) lerp(1, base / lum, sheen_tint)                 (front only)
   Sampling (Mitsuba's probabilities): on the front diffuse : clearcoat : specular = brdf r_d : clearcoat r_c / 4 :
   r_s, the specular part reflecting with probability 1 - bsdf (1-F) at the sampled GGX visible normal; from the
   back (only with a transmitting lobe) reflection with probability F, else refraction. Mitsuba draws the lobe from
   a third uniform number; here u.x picks diffuse/clearcoat/specular (their odds do not depend on F) and is reused,
   and reflection against refraction is decided by mf_extra_uniform(u).
   Where Mitsuba's variants differ (scalar_rgb adds sheen only where the diffuse lobe is on, i.e. not at
   spec_trans = 1; the vectorised variants add it there too) this follows the vectorised ones. */
#ifndef CLRENDER_BSDFS_PRINCIPLED_H
#define CLRENDER_BSDFS_PRINCIPLED_H
#include "common.h"
#include "warp.h"
#include "distribution.h"
#include "principled_common.h"

INLINE MfDist pr_dist(__global const Bsdf* b, const BsdfQuery* q) {
    return pr_ggx(PARAM_FLOAT(q, b->p.principled, roughness), PARAM_FLOAT(q, b->p.principled, anisotropic));
}

/* The half vector of (wi, wo) (reflect: wo on wi's side; else refracted at eta_p), turned to the upper hemisphere */
INLINE vec3 pr_half(vec3 wi, vec3 wo, float eta_p, bool reflect) {
    vec3 h = normalize3(vadd(wi, vscale(wo, reflect ? 1.0f : eta_p)));
    return h.z < 0.0f ? vneg(h) : h;
}

INLINE float pr_gtr1_d(float alpha, float cos_t) {
    float a2 = alpha * alpha;
    float r = (a2 - 1.0f) / (M_PI_F_ * log(a2) * (1.0f + (a2 - 1.0f) * cos_t * cos_t));
    return r * cos_t > 1e-20f ? r : 0.0f;
}

INLINE float pr_ggx1(vec3 v, vec3 h, float alpha) {
    if (dot3(v, h) * v.z <= 0.0f) return 0.0f;
    if (v.z == 1.0f) return 1.0f;
    float c2 = v.z * v.z;
    float t2 = (1.0f - c2) / c2;
    return 2.0f / (1.0f + sqrt(1.0f + alpha * alpha * t2));
}

INLINE float pr_cc_alpha(__global const Bsdf* b, const BsdfQuery* q) {
    float g = PARAM_FLOAT(q, b->p.principled, clearcoat_gloss);
    return 0.1f + g * (0.001f - 0.1f);
}

/* Lobe selection probabilities (reflect, transmit, clearcoat, diffuse), normalised; F at the microfacet. */
INLINE float4 pr_probs(__global const Bsdf* b, float F, bool front, float metallic, float spec_trans,
                       float clearcoat) {
    float bsdf = (1.0f - metallic) * spec_trans, brdf = (1.0f - metallic) * (1.0f - spec_trans);
    bool has_t = b->p.principled.has_spec_trans != 0u;
    float s = b->p.principled.spec_srate;
    float4 p;
    if (front) {
        p = (float4)(s * (1.0f - bsdf * (1.0f - F)), has_t ? s * bsdf * (1.0f - F) : 0.0f,
                     0.25f * clearcoat * b->p.principled.clearcoat_srate, brdf * b->p.principled.diffuse_srate);
    } else {
        p = (float4)(F, has_t ? 1.0f - F : 0.0f, 0.0f, 0.0f);
    }
    float t = p.x + p.y + p.z + p.w;
    return t > 0.0f ? p / t : (float4)(0.0f);
}

INLINE vec3 principled_eval(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo;
    float ci = wi.z, co = wo.z;
    bool reflect = ci * co > 0.0f, refract = ci * co < 0.0f;
    if (!(reflect || refract)) return v3s(0.0f);
    bool front = ci > 0.0f;
    float eta = b->p.principled.eta;
    float eta_p = front ? eta : 1.0f / eta;
    float metallic = PARAM_FLOAT(q, b->p.principled, metallic);
    float spec_trans = PARAM_FLOAT(q, b->p.principled, spec_trans);
    float bsdf = (1.0f - metallic) * spec_trans, brdf = (1.0f - metallic) * (1.0f - spec_trans);
    vec3 base = param_color(q, b->p.principled.base_color, b->p.principled.base_color_tex);
    vec3 h = pr_half(wi, wo, eta_p, reflect);
    float wih = dot3(wi, h), woh = dot3(wo, h), cos_t;
    float F = fresnel_dielectric(wih, 1.0f, eta, &cos_t);
    bool compatible = pr_compatible(h, wi, wo, reflect);
    MfDist d = pr_dist(b, q);
    float DG = mf_d(d, h) * mf_g1(d, wi, h) * mf_g1(d, wo, h);
    vec3 value = v3s(0.0f);
    float aco = fabs(co), aci = fabs(ci);

    if (reflect && compatible && F > 0.0f) {
        vec3 Fp;
        if (front) {
            float spec_tint = PARAM_FLOAT(q, b->p.principled, spec_tint);
            float lum = luminance(base);
            vec3 tint = lum > 0.0f ? vdivs(base, lum) : v3s(1.0f);
            float eta_it = wih >= 0.0f ? eta : 1.0f / eta;
            float r0 = (eta_it - 1.0f) / (eta_it + 1.0f);
            vec3 s_base = pr_schlick(base, wih, eta);
            vec3 s_tint = pr_schlick(vscale(tint, r0 * r0), wih, eta);
            Fp = vadd(v3s((1.0f - metallic) * (1.0f - spec_tint) * F), vscale(s_base, metallic));
            Fp = vadd(Fp, vscale(s_tint, (1.0f - metallic) * spec_tint));
        } else {
            Fp = v3s(bsdf * F);
        }
        value = vmad(Fp, DG / (4.0f * aci * aco), value);
    }
    if (refract && compatible && bsdf > 0.0f && F < 1.0f) {
        float den = wih + eta_p * woh;
        value = vmad(vsqrt(base), bsdf * fabs((1.0f - F) * DG * wih * woh / (ci * den * den)) / aco, value);
    }
    if (!(reflect && front)) return value;

    float clearcoat = PARAM_FLOAT(q, b->p.principled, clearcoat);
    if (compatible && clearcoat > 0.0f) {
        float Fcc = pr_schlick(v3s(0.04f), wih, eta).x;
        float Dcc = pr_gtr1_d(pr_cc_alpha(b, q), h.z);
        value = vadds(value, 0.25f * clearcoat * Fcc * Dcc * pr_ggx1(wi, h, 0.25f) * pr_ggx1(wo, h, 0.25f));
    }
    float Fo = pr_sw(aco), Fi = pr_sw(aci);
    if (brdf > 0.0f) {
        float f_diff = (1.0f - 0.5f * Fi) * (1.0f - 0.5f * Fo);
        float rr = 2.0f * PARAM_FLOAT(q, b->p.principled, roughness) * woh * woh;
        float f = f_diff + rr * (Fo + Fi + Fo * Fi * (rr - 1.0f));
        float flatness = PARAM_FLOAT(q, b->p.principled, flatness);
        if (flatness != 0.0f) {
            /* Hanrahan-Krueger's fake subsurface, flattening the retro-reflection */
            float fss90 = 0.5f * rr;
            float fss = (1.0f + (fss90 - 1.0f) * Fo) * (1.0f + (fss90 - 1.0f) * Fi);
            float f_ss = 1.25f * (fss * (1.0f / (aco + aci) - 0.5f) + 0.5f);
            f += flatness * (f_ss - f);
        }
        value = vmad(base, brdf * INV_PI * f, value);
    }
    float sheen = PARAM_FLOAT(q, b->p.principled, sheen);
    if (sheen > 0.0f && 1.0f - metallic > 0.0f) {
        float sheen_tint = PARAM_FLOAT(q, b->p.principled, sheen_tint);
        vec3 c = v3s(1.0f);
        if (sheen_tint != 0.0f) {
            float lum = luminance(base);
            vec3 tint = lum > 0.0f ? vdivs(base, lum) : v3s(1.0f);
            c = vlerp(c, tint, sheen_tint);
        }
        value = vmad(c, sheen * (1.0f - metallic) * pr_sw(fabs(woh)), value);
    }
    return value;
}

INLINE float principled_pdf(__global const Bsdf* b, const BsdfQuery* q) {
    vec3 wi = q->wi, wo = q->wo;
    float ci = wi.z, co = wo.z;
    if (ci == 0.0f) return 0.0f;
    bool reflect = ci * co > 0.0f, refract = ci * co < 0.0f;
    bool front = ci > 0.0f;
    float eta = b->p.principled.eta;
    float eta_p = front ? eta : 1.0f / eta;
    vec3 h = pr_half(wi, wo, eta_p, reflect);
    float wih = dot3(wi, h), woh = dot3(wo, h), cos_t;
    float F = fresnel_dielectric(wih, 1.0f, eta, &cos_t);
    float clearcoat = PARAM_FLOAT(q, b->p.principled, clearcoat);
    float4 p = pr_probs(b, F, front, PARAM_FLOAT(q, b->p.principled, metallic),
                        PARAM_FLOAT(q, b->p.principled, spec_trans), clearcoat);
    float dwh;
    if (reflect) {
        dwh = fabs(1.0f / (4.0f * woh));
    } else {
        float den = wih + eta_p * woh;
        dwh = fabs(eta_p * eta_p * woh / (den * den));
    }
    float pdf = 0.0f;
    bool compatible = pr_compatible(h, wi, wo, reflect);
    if (compatible && (reflect || refract)) {
        float pm = mf_pdf(pr_dist(b, q), front ? wi : vneg(wi), h) * dwh;
        pdf += (reflect ? p.x : p.y) * pm;
        if (reflect && p.z > 0.0f) pdf += p.z * h.z * pr_gtr1_d(pr_cc_alpha(b, q), h.z) * dwh;
    }
    if (reflect) pdf += p.w * co * INV_PI;
    return pdf;
}

INLINE vec3 principled_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    vec3 wi = q->wi;
    q->eta = 1.0f;
    q->measure = MEASURE_SOLID_ANGLE;
    q->wo = reflect_local(wi);
    float ci = wi.z;
    if (ci == 0.0f) return v3s(0.0f);
    bool front = ci > 0.0f;
    float eta = b->p.principled.eta;
    float metallic = PARAM_FLOAT(q, b->p.principled, metallic);
    float spec_trans = PARAM_FLOAT(q, b->p.principled, spec_trans);
    if (!front && !((1.0f - metallic) * spec_trans > 0.0f && b->p.principled.has_spec_trans)) return v3s(0.0f);
    /* diffuse and clearcoat odds, and the specular lobe's as a whole, do not depend on F */
    float4 p = pr_probs(b, 0.0f, front, metallic, spec_trans, PARAM_FLOAT(q, b->p.principled, clearcoat));
    float ps = p.x + p.y;
    vec3 wo;
    if (u.x < p.w) {
        wo = square_to_cosine_hemisphere((float2)(u.x / p.w, u.y));
    } else if (u.x < p.w + p.z) {
        float alpha = pr_cc_alpha(b, q), a2 = alpha * alpha;
        float ux = (u.x - p.w) / p.z;
        /* GTR1's normals: phi from the first number, cos^2 theta from the second (Mitsuba's order) */
        float c2 = (1.0f - pow(a2, 1.0f - u.y)) / (1.0f - a2);
        float st = safe_sqrt(1.0f - c2), ct = safe_sqrt(c2);
        float2 sc = sin_cos(2.0f * M_PI_F_ * ux);
        vec3 m = v3(sc.y * st, sc.x * st, ct);
        wo = vsub(vscale(m, 2.0f * dot3(wi, m)), wi);
        if (!(dot3(wi, m) > 0.0f && dot3(wo, m) > 0.0f && wo.z > 0.0f)) return v3s(0.0f);
    } else {
        float2 v = (float2)(ps < 1.0f ? minf((u.x - p.w - p.z) / ps, 0.99999994f) : u.x, u.y);
        vec3 m = mf_sample(pr_dist(b, q), front ? wi : vneg(wi), v);
        float wim = dot3(wi, m), cos_t;
        float F = fresnel_dielectric(wim, 1.0f, eta, &cos_t);
        float bsdf = (1.0f - metallic) * spec_trans;
        float p_refl = front ? 1.0f - bsdf * (1.0f - F) : F;
        if (mf_extra_uniform(u) < p_refl) {
            wo = vsub(vscale(m, 2.0f * wim), wi);
            if (!pr_compatible(m, wi, wo, true) || !(wo.z * ci > 0.0f)) return v3s(0.0f);
        } else {
            float r = wim >= 0.0f ? 1.0f / eta : eta;
            wo = normalize3(refract_about(wi, m, r, cos_t));
            q->eta = 1.0f / r;
            if (!pr_compatible(m, wi, wo, false) || !(wo.z * ci < 0.0f)) return v3s(0.0f);
        }
    }
    if (!(wo.z * ci != 0.0f)) return v3s(0.0f);
    q->wo = wo;
    return bsdf_sample_weight(principled_eval(b, q), wo.z, principled_pdf(b, q));
}

INLINE vec3 principled_albedo(__global const Bsdf* b, const BsdfQuery* q) {
    return param_color(q, b->p.principled.base_color, b->p.principled.base_color_tex);
}

#endif
