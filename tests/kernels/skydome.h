/* A test-only infinite emitter (tests/test_plugins.py): radiance L from the upper hemisphere (+y), nothing from
   below, sampled uniformly over that hemisphere (pdf 1/(2 pi)). Row: p.skydome.radiance. */
#ifndef CLRENDER_TEST_SKYDOME_H
#define CLRENDER_TEST_SKYDOME_H
#include "emitters/common.h"

INLINE vec3 skydome_sample(const SceneData* sd, __global const Emitter* em, EmitterQuery* q, float2 u) {
    vec3 h = square_to_uniform_hemisphere(u);           /* about +z */
    vec3 wi = v3(h.x, h.z, h.y);                    /* about +y */
    q->wi = wi;
    q->p = vmad(wi, emitter_far(sd, q->ref), q->ref);
    q->n = vneg(wi);
    q->ng = vneg(wi);
    q->dist = INFINITY;
    q->pdf = 0.5f * INV_PI;
    return vscale(vxyz(em->p.skydome.radiance), 2.0f * M_PI_F_);
}

INLINE float skydome_pdf(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return q->wi.y > 0.0f ? 0.5f * INV_PI : 0.0f;
}

INLINE vec3 skydome_eval(const SceneData* sd, __global const Emitter* em, const EmitterQuery* q) {
    return q->wi.y > 0.0f ? vxyz(em->p.skydome.radiance) : v3s(0.0f);
}

#endif
