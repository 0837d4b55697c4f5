/* Mitsuba 3's spot light (clrender/emitters/spot.py): a point light whose intensity falls off linearly in angle
   between the beam width and the cutoff about its local +z.

   Emitter row: flags EMITTER_DELTA; p.spot: intensity.xyz = I; position.xyz, position.w = 1 / (cutoff - beam);
   inv[0..2].xyz = rows of the inverse of to_world's linear part; inv[0].w = cos cutoff, inv[1].w = cos beam,
   inv[2].w = cutoff (radians).
   sample: wi toward the light, returns I falloff(-wi) / dist^2 with pdf 1 and delta = 1. */
#ifndef CLRENDER_EMITTERS_SPOT_H
#define CLRENDER_EMITTERS_SPOT_H
#include "common.h"

/* Falloff of the world direction d leaving the light. */
INLINE float spot_falloff(__global const Emitter* em, float3 d) {
    float3 ld = normalize3((float3)(dot3(em->p.spot.inv[0].xyz, d), dot3(em->p.spot.inv[1].xyz, d),
                                       dot3(em->p.spot.inv[2].xyz, d)));
    float c = ld.z;
    if (!(c > em->p.spot.inv[0].w)) return 0.0f;
    if (c >= em->p.spot.inv[1].w) return 1.0f;
    return (em->p.spot.inv[2].w - acos(clampf(c, -1.0f, 1.0f))) * em->p.spot.position.w;
}

INLINE float3 spot_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    float inv_d2 = emitter_point_query(q, em->p.spot.position.xyz);
    if (!(inv_d2 > 0.0f)) return (float3)(0.0f);
    return em->p.spot.intensity.xyz * (spot_falloff(em, -q->wi) * inv_d2);
}

#endif
