/* Test kernel (clrender/testing/media.py): tracking through medium row `medium` of a packed scene along the ray
   o + t d, t in [0, t1], in bulk. mode 0: ratio tracking's transmittance estimate (xyz); mode 1: delta tracking's
   first real collision for channel `channel` (x: its distance, INFINITY if none before t1). */
#include "rng.h"
#include "scene.h"
#include "media/tracking.h"
__kernel void medium_track_batch(SCENE_ARGS, uint medium, float4 o, float4 d, float t1, uint channel, uint mode,
                                 uint n, uint first, uint seed, __global float4* out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    Sampler s;
    sampler_init(&s, seed, first + i, 0u);
    __global const Medium* m = sd.media + medium;
    vec3 ro = vxyz(o), rd = vxyz(d);
    if (mode == 0u) {
        out[i] = vf4(medium_ratio_tracking(&sd, m, ro, rd, t1, &s), 0.0f);
        return;
    }
    float t = 0.0f, end = t1;
    float mu = medium_track_range(&sd, m, ro, rd, &t, &end);
    float hit = INFINITY;
    vec3 sigma;
    bool real = false;
    for (int k = 0; mu > 0.0f && k < MEDIA_MAX_NULL_COLLISIONS; ++k) {
        if (!medium_track_step(&sd, m, ro, rd, mu, end, channel, &s, &t, &sigma, &real)) break;
        if (real) { hit = t; break; }
    }
    out[i] = (float4)(hit, 0.0f, 0.0f, 0.0f);
}
