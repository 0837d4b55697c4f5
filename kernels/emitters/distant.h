/* Distant (directional) light, an extension: parallel light travelling along `direction`, irradiance E on a
   surface perpendicular to it. A delta light in direction.

   Emitter row: flags EMITTER_DELTA; p.distant.irradiance.xyz = E (rgb); p.distant.direction.xyz = unit direction
   of travel.
   sample: wi = -direction, dist = INFINITY, returns E with pdf 1 and delta = 1. */
#ifndef CLRENDER_EMITTERS_DISTANT_H
#define CLRENDER_EMITTERS_DISTANT_H
#include "common.h"

INLINE vec3 distant_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    vec3 wi = vneg(vrow(em->p.distant.direction));
    q->wi = wi;
    q->p = vmad(wi, emitter_far(sd, q->ref), q->ref);
    q->n = vneg(wi);
    q->ng = vneg(wi);
    q->dist = INFINITY;
    q->pdf = 1.0f;
    q->delta = 1u;
    return vrow(em->p.distant.irradiance);
}

#endif
