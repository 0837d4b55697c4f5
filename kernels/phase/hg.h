/* hg: Henyey-Greenstein, p(wo) = (1 - g^2) / (4 pi (1 + g^2 + 2 g cos)^(3/2)) with cos = dot(wo, wi), so g > 0
   scatters forward (toward -wi). Sampled by inverting its CDF in cos (weight 1). Row: p.hg.g. */
#ifndef CLRENDER_PHASE_HG_H
#define CLRENDER_PHASE_HG_H
#include "phase/common.h"

INLINE float hg_value(float g, float cos_theta) {
    float t = 1.0f + g * g + 2.0f * g * cos_theta;
    return INV_FOURPI * (1.0f - g * g) / (t * sqrt(t));
}

INLINE float hg_eval(__global const Phase* ph, const PhaseQuery* q) { return hg_value(ph->p.hg.g, dot3(q->wo, q->wi)); }

INLINE float hg_sample(__global const Phase* ph, PhaseQuery* q, float2 u) {
    float g = ph->p.hg.g;
    /* cos_f: the cosine to the forward direction -wi; near g = 0 the inversion divides 0 by 0, and the
       distribution is nearly uniform there, so it is sampled uniformly and weighted by value / pdf */
    bool uniform = fabs(g) < 1e-3f;
    float cos_f;
    if (uniform) {
        cos_f = 1.0f - 2.0f * u.x;
    } else {
        float s = (1.0f - g * g) / (1.0f - g + 2.0f * g * u.x);
        cos_f = clamp((1.0f + g * g - s * s) / (2.0f * g), -1.0f, 1.0f);
    }
    float sin_f = safe_sqrt(1.0f - cos_f * cos_f);
    float2 sc = sin_cos(2.0f * M_PI_F_ * u.y);
    Frame f = frame_from_normal(vneg(q->wi));
    q->wo = normalize3(to_world(&f, v3(sin_f * sc.y, sin_f * sc.x, cos_f)));
    float value = hg_value(g, -cos_f);
    q->pdf = uniform ? INV_FOURPI : value;
    return value / q->pdf;
}
#endif
