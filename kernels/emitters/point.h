/* Point light (delta in position): intensity I = Phi / (4 pi) in every direction.

   Emitter row: flags EMITTER_DELTA; p.point: intensity.xyz = I = Phi / (4 pi) (rgb); position.xyz;
   power.xyz = Phi (for reference).
   sample: wi toward the light, dist = distance, returns I / dist^2 with pdf 1 and delta = 1. */
#ifndef CLRENDER_EMITTERS_POINT_H
#define CLRENDER_EMITTERS_POINT_H
#include "common.h"

INLINE float3 point_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    float3 p = em->p.point.position.xyz;
    float3 d = p - q->ref;
    float d2 = dot3(d, d);
    float l = sqrt(d2);
    q->p = p;
    q->wi = l > 0.0f ? d * (1.0f / l) : (float3)(0.0f, 0.0f, 1.0f);
    q->n = -q->wi;
    q->ng = -q->wi;
    q->dist = l;
    q->pdf = 1.0f;
    q->delta = 1u;
    return d2 > 0.0f ? em->p.point.intensity.xyz * (1.0f / d2) : (float3)(0.0f);
}

#endif
