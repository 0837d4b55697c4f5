/* The render kernels: the integrator chosen at build time (li.h) over pixels, with the film's filter. */
#include "li.h"
#include "filter.h"
#ifdef CLR_FEATURE_AOVS
#include "feature_aovs.h"
#endif

/* `spp` samples of pixel `pix`, numbered from `sample_offset`, added to its accumulators (FILM_ARGS: the film's
   per-pixel accumulators acc0, acc1, bad and rays, declared with what each holds in clrender/device/layout.py
   FILM_ACCUMULATORS; rays is written only in builds with -DCLRENDER_COUNT_RAYS). filter_cdf is the filter's CDF
   followed by its guide (clrender/filters/filter.py). The first closest-hit query of a sample is its camera ray. The
   samples of one call are summed first and added to the accumulators once, so a pixel's sums depend only on how its
   samples are cut into calls, never on which other pixels share a launch. */
inline void render_pixel(SceneData* sd, __global const Camera* cam, __global const float* filter_cdf, FILM_ARGS,
                         uint pix, uint sample_offset, uint spp, uint seed) {
    uint px = pix % cam->width, py = pix / cam->width;
    vec3 swl = v3s(0.0f), swl2 = v3s(0.0f);
    float sw = 0.0f;
    uint nbad = 0u;
#ifdef CLRENDER_COUNT_RAYS
    uint n_camera = 0u, n_closest = 0u, n_shadow = 0u;
#endif
    for (uint s = 0u; s < spp; ++s) {
        Sampler smp;
        sampler_init(&smp, seed, pix, sample_offset + s);
        float w;
        Ray ray;
        if (!camera_sample(cam, filter_cdf, px, py, &smp, &w, &ray)) continue;   /* weight 0 */
#ifdef CLRENDER_COUNT_RAYS
        sd->n_closest = 0u;
        sd->n_shadow = 0u;
#endif
        vec3 L = Li(sd, ray, &smp);
#ifdef CLRENDER_COUNT_RAYS
        uint cam_ray = sd->n_closest > 0u ? 1u : 0u;
        n_camera += cam_ray;
        n_closest += sd->n_closest - cam_ray;
        n_shadow += sd->n_shadow;
#endif
#ifdef CLRENDER_TEST_POISON
        /* test builds only: prove that bad samples are dropped and counted */
        uint si = sample_offset + s;
        if (si % 5u == 0u) L.x = NAN;
        else if (si % 7u == 0u) L.y = INFINITY;
#endif
        if (!all_finite(L) || !isfinite(w)) { nbad += 1u; continue; }
        vec3 wl = vscale(L, w);
        swl = vadd(swl, wl);
        swl2 = vadd(swl2, vmul(wl, wl));
        sw += w;
    }
    float4 a0 = acc0[pix], a1 = acc1[pix];
    acc0[pix] = vf4(vadd(vxyz(a0), swl), a0.w + sw);
    acc1[pix] = vf4(vadd(vxyz(a1), swl2), a1.w + (float)(spp - nbad));
    bad[pix] += nbad;
#ifdef CLRENDER_COUNT_RAYS
    rays[pix] += (uint4)(n_camera, n_closest, n_shadow, 0u);
#endif
}

/* One pass: `spp` samples for each of `pixel_count` pixels starting at `pixel_offset`. Each work-item owns one pixel,
   so accumulation needs no atomics. */
__kernel void render_pass(SCENE_ARGS, __global const Camera* cam, __global const float* filter_cdf, FILM_ARGS,
                          uint pixel_offset, uint pixel_count, uint sample_offset, uint spp, uint seed) {
    uint gid = get_global_id(0);
    if (gid >= pixel_count) return;
    SCENE_INIT(sd);
    render_pixel(&sd, cam, filter_cdf, acc0, acc1, bad, rays, pixel_offset + gid, sample_offset, spp, seed);
}

/* The same over a list of pixels (adaptive sampling's round: the pixels that still need samples):
   pixel_list[pixel_offset .. pixel_offset + pixel_count), each pixel at most once per launch. */
__kernel void render_list(SCENE_ARGS, __global const Camera* cam, __global const float* filter_cdf, FILM_ARGS,
                          __global const uint* pixel_list, uint pixel_offset, uint pixel_count, uint sample_offset,
                          uint spp, uint seed) {
    uint gid = get_global_id(0);
    if (gid >= pixel_count) return;
    SCENE_INIT(sd);
    render_pixel(&sd, cam, filter_cdf, acc0, acc1, bad, rays, pixel_list[pixel_offset + gid], sample_offset, spp,
                 seed);
}

/* The same with each listed pixel's own samples: entry i adds samples spans[i].x .. spans[i].x + spans[i].y - 1 to
   pixel_list[i] (adaptive sampling after its first round: each pixel to the count its estimate predicts, in one
   call, so a round is one launch however unequal the pixels' needs; a pixel's sums depend on its spans only). */
__kernel void render_spans(SCENE_ARGS, __global const Camera* cam, __global const float* filter_cdf, FILM_ARGS,
                           __global const uint* pixel_list, __global const uint2* spans, uint pixel_offset,
                           uint pixel_count, uint seed) {
    uint gid = get_global_id(0);
    if (gid >= pixel_count) return;
    SCENE_INIT(sd);
    uint2 span = spans[pixel_offset + gid];
    render_pixel(&sd, cam, filter_cdf, acc0, acc1, bad, rays, pixel_list[pixel_offset + gid], span.x, span.y, seed);
}
