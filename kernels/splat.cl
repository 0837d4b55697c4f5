/* A splatting film (Mitsuba's and Nori's reconstruction): each sample is placed uniformly inside its pixel and
   counts, with the filter's weight f(dx) f(dy), in every pixel whose centre lies within the filter's radius, so a
   wide filter (Mitsuba's default Gaussian reaches 2 pixels) lets every pixel average about three times the
   samples that filter importance sampling (render.cl) gives it, at the same expected image.

   Done without atomics and without depending on how a pass is cut into launches: render_records writes each
   sample's radiance to a buffer of the pass (one float4 per pixel and sample), and splat_gather sums, for each
   pixel, the records of its neighbours in a fixed order (rows, columns, samples), recomputing each sample's
   position from its random numbers instead of storing it. Built with -DCLR_SPLAT instead of render.cl's kernels
   (one integrator inlined per program). */
#include "li.h"
#include "filter.h"
#ifdef CLR_FEATURE_AOVS
#include "feature_aovs.h"
#endif

/* Pixels from which a sample can reach a pixel: |offset| <= splat_reach in x and y. */
INLINE int splat_reach(__global const Camera* cam) {
    return (int)ceil(cam->filter_radius - 0.5f);
}

/* Each sample's record: its radiance with w = 1, or 0 for a NaN/Inf sample (dropped, counted in its own pixel),
   and its filter weights toward the pixels within reach: weights[(2 reach + 1) (2 i + a) + reach + t] is
   f(pixel's centre + t - the sample's position) along axis a (x, y) for the sample at record i, 0 for a dropped
   sample. Computed here once per sample, so splat_gather only multiplies and adds. */
__kernel void render_records(SCENE_ARGS, __global const Camera* cam, __global float4* records,
                             __global float* weights, uint rec_base, uint pixel_offset, uint pixel_count,
                             uint sample_offset, uint spp, uint seed) {
    uint gid = get_global_id(0);
    if (gid >= pixel_count) return;
    SCENE_INIT(sd);
    uint pix = pixel_offset + gid;
    uint px = pix % cam->width, py = pix / cam->width;
    int reach = splat_reach(cam);
    uint k = 2u * (uint)reach + 1u;
    size_t first = (size_t)(pix - rec_base) * spp;
    for (uint s = 0u; s < spp; ++s) {
        Sampler smp;
        sampler_init(&smp, seed, pix, sample_offset + s);
        float2 u = next2d(&smp);
        float2 lens = cam->lens_radius > 0.0f ? next2d(&smp) : (float2)(0.5f, 0.5f);
        Ray ray = camera_ray_lens(cam, (float)px + u.x, (float)py + u.y, lens);
        vec3 L = Li(&sd, ray, &smp);
#ifdef CLRENDER_TEST_POISON
        uint si = sample_offset + s;
        if (si % 5u == 0u) L.x = NAN;
        else if (si % 7u == 0u) L.y = INFINITY;
#endif
        bool ok = all_finite(L);
        records[first + s] = ok ? vf4(L, 1.0f) : (float4)(0.0f);
        __global float* wt = weights + (first + s) * 2u * k;
        for (int t = -reach; t <= reach; ++t) {
            wt[reach + t] = ok ? filter_eval_1d(cam, (float)t + 0.5f - u.x) : 0.0f;
            wt[k + reach + t] = ok ? filter_eval_1d(cam, (float)t + 0.5f - u.y) : 0.0f;
        }
    }
}

/* Pixels pixel_offset .. + pixel_count: the pass's records of every neighbour within reach (the records hold
   pixels rec_first .. rec_stop - 1, pixel p at (p - rec_base) * spp) added to the film's sums (SPLAT_FILM_ARGS, clrender/device/layout.py): acc0 (sum w L, sum w),
   acc1 (sum (w L)^2, own samples), acc2 (sum w^2 L, sum w^2: with acc1 the variance of the ratio), bad. */
__kernel void splat_gather(__global const Camera* cam, __global const float4* records, __global const float* weights,
                           uint rec_base, uint rec_first, uint rec_stop, SPLAT_FILM_ARGS, uint pixel_offset,
                           uint pixel_count, uint sample_offset, uint spp, uint seed) {
    uint gid = get_global_id(0);
    if (gid >= pixel_count) return;
    uint q = pixel_offset + gid;
    int w = (int)cam->width, h = (int)cam->height;
    int qx = (int)(q % cam->width), qy = (int)(q / cam->width);
    int reach = splat_reach(cam);
    uint k = 2u * (uint)reach + 1u;
    vec3 swl = v3s(0.0f), swl2 = v3s(0.0f), sw2l = v3s(0.0f);
    float sw = 0.0f, sw2 = 0.0f;
    uint own = 0u;
    for (int y = max(qy - reach, 0); y <= min(qy + reach, h - 1); ++y) {
        for (int x = max(qx - reach, 0); x <= min(qx + reach, w - 1); ++x) {
            uint p = (uint)(y * w + x);
            if (p < rec_first || p >= rec_stop) continue;
            size_t first = (size_t)(p - rec_base) * spp;
            uint ix = (uint)(reach + qx - x), iy = k + (uint)(reach + qy - y);
            for (uint s = 0u; s < spp; ++s) {
                float4 r = records[first + s];
                __global const float* wt = weights + (first + s) * 2u * k;
                float fw = wt[ix] * wt[iy];
                vec3 wl = vscale(vxyz(r), fw);
                swl = vadd(swl, wl);
                swl2 = vadd(swl2, vmul(wl, wl));
                sw2l = vadd(sw2l, vscale(wl, fw));
                sw += fw;
                sw2 += fw * fw;
                if (p == q) own += r.w > 0.0f ? 1u : 0u;
            }
        }
    }
    float4 a0 = acc0[q], a1 = acc1[q], a2 = acc2[q];
    acc0[q] = vf4(vadd(vxyz(a0), swl), a0.w + sw);
    acc1[q] = vf4(vadd(vxyz(a1), swl2), a1.w + (float)own);
    acc2[q] = vf4(vadd(vxyz(a2), sw2l), a2.w + sw2);
    if (q >= rec_first && q < rec_stop) bad[q] += spp - own;
}
