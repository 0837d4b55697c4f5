/* Perfect specular reflection: wo = (-x, -y, z), weight 1, discrete measure (eval and pdf are 0). */
#ifndef CLRENDER_BSDFS_MIRROR_H
#define CLRENDER_BSDFS_MIRROR_H
#include "common.h"

INLINE vec3 mirror_sample(__global const Bsdf* b, BsdfQuery* q, float2 u) {
    q->measure = MEASURE_DISCRETE;
    q->eta = 1.0f;
    q->wo = reflect_local(q->wi);
    return q->wi.z <= 0.0f ? v3s(0.0f) : v3s(1.0f);
}

#endif
