/* Constant environment, an extension: radiance L from every direction (furnace tests, a uniform sky).

   Emitter row: flags EMITTER_INFINITE; p.constant_.radiance.xyz = L (`constant` is an OpenCL keyword).
   sample: uniform on the sphere, pdf 1 / (4 pi), returns 4 pi L, dist = INFINITY. */
#ifndef CLRENDER_EMITTERS_CONSTANT_H
#define CLRENDER_EMITTERS_CONSTANT_H
#include "common.h"

INLINE vec3 constant_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    vec3 wi = square_to_uniform_sphere(u);
    q->wi = wi;
    q->p = vmad(wi, emitter_far(sd, q->ref), q->ref);
    q->n = vneg(wi);
    q->ng = vneg(wi);
    q->dist = INFINITY;
    q->pdf = INV_FOURPI;
    return vscale(vrow(em->p.constant_.radiance), 4.0f * M_PI_F_);
}

INLINE float constant_pdf(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return INV_FOURPI;
}

INLINE vec3 constant_eval(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return vrow(em->p.constant_.radiance);
}

#endif
