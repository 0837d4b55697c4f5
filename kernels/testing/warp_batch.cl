/* Test kernels (clrender/testing/kernels.py, `clrender warptest`): the warping functions of warp.h and their
   densities in bulk. */
#include "rng.h"
#include "warp.h"

/* kind: 0 square, 1 tent, 2 disk, 3 sphere, 4 hemisphere, 5 cosine hemisphere, 6 cone (param = cos_max),
   7 triangle (barycentrics), 8 Beckmann (param = alpha). 2-D results in .xy, directions in .xyz. */
INLINE float4 warp_point(uint kind, float param, float2 u) {
    switch (kind) {
        case 0: return (float4)(square_to_uniform_square(u), 0.0f, 0.0f);
        case 1: return (float4)(square_to_tent(u), 0.0f, 0.0f);
        case 2: return (float4)(square_to_uniform_disk(u), 0.0f, 0.0f);
        case 3: return vf4(square_to_uniform_sphere(u), 0.0f);
        case 4: return vf4(square_to_uniform_hemisphere(u), 0.0f);
        case 5: return vf4(square_to_cosine_hemisphere(u), 0.0f);
        case 6: return vf4(square_to_uniform_cone(u, param), 0.0f);
        case 7: return (float4)(square_to_uniform_triangle(u), 0.0f, 0.0f);
        default: return vf4(square_to_beckmann(u, param), 0.0f);
    }
}
INLINE float warp_density(uint kind, float param, float4 p) {
    switch (kind) {
        case 0: return square_to_uniform_square_pdf(p.xy);
        case 1: return square_to_tent_pdf(p.xy);
        case 2: return square_to_uniform_disk_pdf(p.xy);
        case 3: return square_to_uniform_sphere_pdf(vxyz(p));
        case 4: return square_to_uniform_hemisphere_pdf(vxyz(p));
        case 5: return square_to_cosine_hemisphere_pdf(vxyz(p));
        case 6: return square_to_uniform_cone_pdf(vxyz(p), param);
        case 7: return square_to_uniform_triangle_pdf(p.xy);
        default: return square_to_beckmann_pdf(vxyz(p), param);
    }
}
__kernel void warp_sample_batch(uint kind, float param, uint n, uint first, uint seed, __global float4* out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    Sampler s;
    sampler_init(&s, seed, first + i, 0u);
    out[i] = warp_point(kind, param, next2d(&s));
}
__kernel void warp_pdf_batch(uint kind, float param, uint n, __global const float4* pts, __global float* out) {
    uint i = get_global_id(0);
    if (i >= n) return;
    out[i] = warp_density(kind, param, pts[i]);
}
