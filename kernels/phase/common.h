/* What every phase function kernel shares: the query record. Directions are unit vectors in world space; wi
   points back along the path (= -ray.d at the scattering point), wo is the sampled or queried direction, so
   forward scattering is wo = -wi (Mitsuba's convention, whose hg takes cos = dot(wo, wi)). */
#ifndef CLRENDER_PHASE_COMMON_H
#define CLRENDER_PHASE_COMMON_H
#include "math.h"
#include "warp.h"
#include "frame.h"

typedef struct {
    vec3 wi;
    vec3 wo;
    float pdf;   /* solid-angle density of wo under phase_sample (set by sample) */
} PhaseQuery;

#endif
