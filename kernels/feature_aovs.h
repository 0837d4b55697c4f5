/* Feature AOVs for denoisers (built only with -DCLR_FEATURE_AOVS, so programs that render without them do not
   change): per camera sample, through delta (mirror, smooth glass) bounces, the first non-specular vertex's albedo
   (one BSDF sample's weight f cos / pdf: an unbiased estimate of its directional reflectance, exact for a diffuse
   colour under cosine sampling; times the delta bounces' weights, so a mirror shows what it sees tinted by its own
   reflectance) and world-space shading normal; and of the camera ray's first hit its distance (Mitsuba's aov
   depth: from the near clip plane) and position. An escaped ray adds zeros. The samples are the beauty pass's
   (same sampler keys: the same camera rays), weighted by the same filter weight. Per pixel, three float4:
   (sum w albedo, sum w depth), (sum w normal, sum w), (sum w position, 0). */
#ifndef CLRENDER_FEATURE_AOVS_H
#define CLRENDER_FEATURE_AOVS_H
/* The features do not depend on the integrator, so the BSDF queries come from here and not from whichever
   integrator this program was built with: ao, av, normals or simple never include lighting.h themselves. */
#include "integrators/lighting.h"

#define FEATURE_MAX_DELTA_BOUNCES 16

INLINE void feature_sample(const SceneData* sd, Ray ray, Sampler* smp, vec3* albedo, vec3* normal, float* depth,
                           vec3* position) {
    *albedo = *normal = *position = v3s(0.0f);
    *depth = 0.0f;
    vec3 thr = v3s(1.0f);
    for (uint k = 0u; k <= FEATURE_MAX_DELTA_BOUNCES; ++k) {
        Intersection its;
        if (!scene_intersect(sd, &ray, &its)) return;
        if (k == 0u) {
            *depth = its.t - ray.tmin;
            *position = its.p;
        }
        __global const Bsdf* b = bsdf_at(sd, &its);
        BsdfQuery q = bsdf_query(sd, &its, vneg(ray.d));
        vec3 w = bsdf_sample(b, &q, next2d(smp));
        if (!bsdf_is_delta(b)) {
            *albedo = vmul(thr, w);
            *normal = its.sh.n;
            return;
        }
        if (is_black(w)) return;
        thr = vmul(thr, w);
        ray = spawn_ray_from(&its, to_world(&its.sh, q.wo));
    }
}

/* `spp` feature samples of each pixel of the launch (pixel_offset + i, or pixel_list[pixel_offset + i] when
   `listed`), numbered from sample_offset as the beauty pass's, added to aov[3 pix .. 3 pix + 2]. */
__kernel void feature_pass(SCENE_ARGS, __global const Camera* cam, __global const float* filter_cdf,
                           __global float4* aov, __global const uint* pixel_list, uint listed, uint pixel_offset,
                           uint pixel_count, uint sample_offset, uint spp, uint seed) {
    uint gid = get_global_id(0);
    if (gid >= pixel_count) return;
    SCENE_INIT(sd);
    uint pix = listed ? pixel_list[pixel_offset + gid] : pixel_offset + gid;
    float4 a0 = (float4)(0.0f), a1 = (float4)(0.0f), a2 = (float4)(0.0f);
    for (uint s = 0u; s < spp; ++s) {
        Sampler smp;
        sampler_init(&smp, seed, pix, sample_offset + s);
        float w;
        Ray ray;
        if (!camera_sample(cam, filter_cdf, pix % cam->width, pix / cam->width, &smp, &w, &ray)) continue;
        vec3 albedo, normal, position;
        float depth;
        feature_sample(&sd, ray, &smp, &albedo, &normal, &depth, &position);
        if (!all_finite(albedo) || !all_finite(normal) || !all_finite(position) || !isfinite(depth) || !isfinite(w))
            continue;
        a0 += vf4(vscale(albedo, w), w * depth);
        a1 += vf4(vscale(normal, w), w);
        a2 += vf4(vscale(position, w), 0.0f);
    }
    aov[3u * pix] += a0;
    aov[3u * pix + 1u] += a1;
    aov[3u * pix + 2u] += a2;
}
#endif
