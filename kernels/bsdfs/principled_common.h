/* What Mitsuba 3's principled and principledthin BSDFs share (Mitsuba's principledhelpers): Schlick's weight and
   approximation, luminance, the macro/micro-surface side test and the GGX distribution of roughness and anisotropy. */
#ifndef CLRENDER_BSDFS_PRINCIPLED_COMMON_H
#define CLRENDER_BSDFS_PRINCIPLED_COMMON_H
#include "common.h"
#include "distribution.h"

/* Mitsuba's calc_dist_params: alpha = max(1e-3, roughness^2), stretched by sqrt(1 - 0.9 anisotropic); sampled from
   the visible normals */
INLINE MfDist pr_ggx(float roughness, float anisotropic) {
    float r2 = roughness * roughness;
    float aspect = sqrt(1.0f - 0.9f * anisotropic);
    MfDist d;
    d.type = MF_GGX;
    d.ax = maxf(1e-3f, r2 / aspect);
    d.ay = maxf(1e-3f, r2 * aspect);
    d.visible = true;
    return d;
}

INLINE float pr_sw(float c) {
    float m = clamp(1.0f - c, 0.0f, 1.0f);
    float m2 = m * m;
    return m2 * m2 * m;
}

/* Mitsuba's calc_schlick: Schlick's approximation with the cosine on the denser side (cos_t inside-out) */
INLINE vec3 pr_schlick(vec3 r0, float cos_i, float eta) {
    float eta_it = cos_i >= 0.0f ? eta : 1.0f / eta;
    float c;
    if (eta_it > 1.0f) {
        c = fabs(cos_i);
    } else {
        float r = 1.0f / eta_it;
        c = safe_sqrt(1.0f - (1.0f - cos_i * cos_i) * r * r);
    }
    float w = pr_sw(c);
    return vmad(vsub(v3s(1.0f), r0), w, r0);
}

/* Mitsuba's mac_mic_compatibility: wi on the front of h (h as seen from wi's side) and wo on the front (reflection)
   or the back (refraction) */
INLINE bool pr_compatible(vec3 h, vec3 wi, vec3 wo, bool reflect) {
    vec3 hs = wi.z > 0.0f ? h : vneg(h);
    float o = dot3(wo, hs);
    return dot3(wi, hs) > 0.0f && (reflect ? o > 0.0f : o < 0.0f);
}

#endif
