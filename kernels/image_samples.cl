/* Nori's ttest of a whole scene: each sample is a film position drawn uniformly over the whole image
   [0,W)x[0,H) (no reconstruction filter, no pixel footprint) and its camera ray's Li (a perspective camera's
   sampleRay weight is 1). One work-item per sample; samples are numbered from `first` in one stream, so a
   split into launches does not change them. NaN/Inf values are returned as they are: the caller counts them. */
#include "li.h"

__kernel void image_samples(SCENE_ARGS, __global const Camera* cam, __global float4* out, uint first, uint n,
                            uint seed) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    Sampler smp;
    sampler_init(&smp, seed, 0u, first + i);
    float2 u = next2d(&smp);
    Ray ray = camera_ray(cam, u.x * (float)cam->width, u.y * (float)cam->height);
    vec3 L = Li(&sd, ray, &smp);
    out[i] = vf4(L, 0.0f);
}
