/* Tracking through a medium that is not homogeneous (kernels/integrators/media.h): tentative collisions at the rate
   of the medium's majorant mu (one bound for every channel, Mitsuba's get_majorant) within the part of the ray
   medium_clip leaves (Mitsuba's intersect_aabb). Delta tracking takes a tentative collision as a real one with
   probability sigma_t / mu, else as a null one; ratio tracking multiplies the transmittance by (mu - sigma_t) / mu
   at each (Mitsuba's volpath: sigma_n / majorant). Shared with the test kernel kernels/testing/media_batch.cl. */
#ifndef CLRENDER_MEDIA_TRACKING_H
#define CLRENDER_MEDIA_TRACKING_H
#include "gen/medium_dispatch.h"

/* Tentative collisions one flight or shadow segment may take; beyond them the path ends (the shadow ray counts as
   blocked). The expected count is the majorant times the length: a bound far above it. */
#define MEDIA_MAX_NULL_COLLISIONS 65536

INLINE float vchannel(vec3 v, uint c) { return c == 0u ? v.x : (c == 1u ? v.y : v.z); }

/* The next tentative collision along o + t d after *t: false if it lies at or beyond t1; else *t moves there,
   *sigma is the extinction there (kept within [0, mu]), and the result says whether channel c takes it as a real
   collision (*real, probability sigma_c / mu). */
INLINE bool medium_track_step(const SceneData* sd, __global const Medium* m, vec3 o, vec3 d, float mu, float t1,
                              uint c, Sampler* smp, float* t, vec3* sigma, bool* real) {
    *t -= log(1.0f - next1d(smp)) / mu;
    if (!(*t < t1)) return false;
    *sigma = vmin(vmax(medium_sigma_t(sd, m, vmad(d, *t, o)), v3s(0.0f)), v3s(mu));
    *real = next1d(smp) * mu < vchannel(*sigma, c);
    return true;
}

/* The segment [*t0, *t1] of o + t d that tracking in m covers and its majorant (0: nothing to track). */
INLINE float medium_track_range(const SceneData* sd, __global const Medium* m, vec3 o, vec3 d, float* t0,
                                float* t1) {
    float mu = medium_majorant(sd, m);
    return (mu > 0.0f && medium_clip(sd, m, o, d, t0, t1)) ? mu : 0.0f;
}

/* Ratio tracking: the transmittance of the segment o + t d, t in [0, t1], of medium m (an unbiased estimate per
   channel; 0 once the loop's bound is reached). */
INLINE vec3 medium_ratio_tracking(const SceneData* sd, __global const Medium* m, vec3 o, vec3 d, float t1,
                                  Sampler* smp) {
    float t = 0.0f;
    float mu = medium_track_range(sd, m, o, d, &t, &t1);
    if (mu == 0.0f) return v3s(1.0f);
    vec3 tr = v3s(1.0f), sigma;
    bool real;
    for (int i = 0; i < MEDIA_MAX_NULL_COLLISIONS; ++i) {
        if (!medium_track_step(sd, m, o, d, mu, t1, 0u, smp, &t, &sigma, &real)) return tr;
        tr = vmul(tr, vscale(vsub(v3s(mu), sigma), 1.0f / mu));
        if (is_black(tr)) return tr;
    }
    return v3s(0.0f);
}
#endif
