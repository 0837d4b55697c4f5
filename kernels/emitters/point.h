/* Point light (delta in position): intensity I = Phi / (4 pi) in every direction.

   Emitter row: flags EMITTER_DELTA; p.point: intensity.xyz = I = Phi / (4 pi) (rgb); position.xyz;
   power.xyz = Phi (for reference).
   sample: wi toward the light, dist = distance, returns I / dist^2 with pdf 1 and delta = 1. */
#ifndef CLRENDER_EMITTERS_POINT_H
#define CLRENDER_EMITTERS_POINT_H
#include "common.h"

INLINE vec3 point_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    return vscale(vrow(em->p.point.intensity), emitter_point_query(q, vrow(em->p.point.position)));
}

#endif
