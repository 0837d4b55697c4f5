/* isotropic: 1 / (4 pi) in every direction, sampled exactly (weight 1). No parameters. */
#ifndef CLRENDER_PHASE_ISOTROPIC_H
#define CLRENDER_PHASE_ISOTROPIC_H
#include "phase/common.h"

INLINE float isotropic_eval(__global const Phase* ph, const PhaseQuery* q) { return INV_FOURPI; }

INLINE float isotropic_sample(__global const Phase* ph, PhaseQuery* q, float2 u) {
    q->wo = square_to_uniform_sphere(u);
    q->pdf = INV_FOURPI;
    return 1.0f;
}
#endif
