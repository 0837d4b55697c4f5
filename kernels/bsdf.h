/* The BSDF interface of the integrators: one switch over the row's type tag (no function pointers).
     bsdf_eval    f (without the cosine); 0 for delta BSDFs
     bsdf_pdf     solid-angle density of wo under bsdf_sample; 0 for delta BSDFs
     bsdf_sample  sets q->wo, q->eta, q->measure and returns f cos(theta_o) / pdf (0 when the sample failed)
     bsdf_is_delta   mirror and dielectric (their samples have q->measure == MEASURE_DISCRETE)
     bsdf_albedo  the diffuse colour including textures (kd for microfacet, 1 for mirror and dielectric)
   All directions are in the local shading frame; q->wi points back along the path (= -ray.d).
   The query record and MEASURE_* are in bsdfs/common.h. */
#ifndef CLRENDER_BSDF_H
#define CLRENDER_BSDF_H
#include "bsdfs/common.h"
#include "bsdfs/texture.h"
#include "bsdfs/diffuse.h"
#include "bsdfs/mirror.h"
#include "bsdfs/dielectric.h"
#include "bsdfs/microfacet.h"

INLINE float3 bsdf_eval(__global const Bsdf* b, const BsdfQuery* q) {
    switch (b->type) {
        case BSDF_DIFFUSE: return diffuse_eval(b, q);
        case BSDF_MICROFACET: return microfacet_eval(b, q);
        default: return (float3)(0.0f);
    }
}

INLINE float bsdf_pdf(__global const Bsdf* b, const BsdfQuery* q) {
    switch (b->type) {
        case BSDF_DIFFUSE: return diffuse_pdf(b, q);
        case BSDF_MICROFACET: return microfacet_pdf(b, q);
        default: return 0.0f;
    }
}

INLINE float3 bsdf_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    switch (b->type) {
        case BSDF_DIFFUSE: return diffuse_sample(b, q, u);
        case BSDF_MIRROR: return mirror_sample(b, q, u);
        case BSDF_DIELECTRIC: return dielectric_sample(b, q, u);
        case BSDF_MICROFACET: return microfacet_sample(b, q, u);
        default:
            q->wo = (float3)(0.0f, 0.0f, 1.0f);
            q->eta = 1.0f;
            q->measure = MEASURE_SOLID_ANGLE;
            return (float3)(0.0f);
    }
}

INLINE bool bsdf_is_delta(__global const Bsdf* b) {
    return b->type == BSDF_MIRROR || b->type == BSDF_DIELECTRIC;
}

INLINE float3 bsdf_albedo(__global const Bsdf* b, float2 uv) {
    switch (b->type) {
        case BSDF_DIFFUSE:
        case BSDF_MICROFACET: return bsdf_color(b, uv);
        default: return (float3)(1.0f);
    }
}

#endif
