/* A test-only BSDF (tests/test_plugins.py): Lambertian reflection of albedo * tint, registered from the test
   suite to show that a BSDF is its .py, its .h and one registration. Row: p.tinted.albedo, p.tinted.tint. */
#ifndef CLRENDER_TEST_TINTED_H
#define CLRENDER_TEST_TINTED_H
#include "bsdfs/common.h"
#include "warp.h"

INLINE vec3 tinted_eval(__global const Bsdf* b, const BsdfQuery* q) {
    if (q->wi.z <= 0.0f || q->wo.z <= 0.0f) return v3s(0.0f);
    vec3 albedo = vxyz(b->p.tinted.albedo);
    return vscale(vscale(albedo, b->p.tinted.tint), INV_PI);
}

INLINE float tinted_pdf(__global const Bsdf* b, const BsdfQuery* q) {
    if (q->wi.z <= 0.0f || q->wo.z <= 0.0f) return 0.0f;
    return q->wo.z * INV_PI;
}

INLINE vec3 tinted_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    q->measure = MEASURE_SOLID_ANGLE;
    q->eta = 1.0f;
    q->wo = square_to_cosine_hemisphere(u);
    if (q->wi.z <= 0.0f || q->wo.z <= 0.0f) return v3s(0.0f);
    return vscale(vxyz(b->p.tinted.albedo), b->p.tinted.tint);
}

#endif
