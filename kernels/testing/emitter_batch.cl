/* Test kernel (clrender/testing/nori.py, `clrender test`): emitter_sample in bulk toward one reference point. */
#include "rng.h"
#include "scene.h"
#include "emitter.h"
__kernel void emitter_sample_batch(SCENE_ARGS, uint e, float4 ref, uint n, uint first, uint seed,
                                   __global float4* out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    Sampler s;
    sampler_init(&s, seed, first + i, 0u);
    EmitterQuery q;
    q.ref = vxyz(ref);
    vec3 w = emitter_sample(&sd, e, &q, next2d(&s));
    out[i] = vf4(w, q.pdf);
}
