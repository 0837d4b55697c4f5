/* A splatting film (Mitsuba's and Nori's reconstruction): each sample is placed uniformly inside its pixel and
   counts, with the filter's weight f(dx) f(dy), in every pixel whose centre lies within the filter's radius, so a
   wide filter (Mitsuba's default Gaussian reaches 2 pixels) lets every pixel average about three times the
   samples that filter importance sampling (render.cl) gives it, at the same expected image.

   Done without atomics and without depending on how a pass is cut into launches: render_records writes each
   sample's radiance to a buffer of the pass (one float4 per pixel and sample), and splat_gather sums, for each
   pixel, the records of its neighbours in a fixed order (rows, columns, samples), recomputing each sample's
   position from its random numbers instead of storing it. Built with -DCLR_SPLAT instead of render.cl's kernels
   (one integrator inlined per program).

   With Mitsuba's sample_border (CLR_SPLAT_BORDER, set by the host) samples are also placed in a border of splat_reach
   pixels around the window, as Mitsuba's film extends its sampled block by the filter's border: the records then
   cover that larger grid, (width + 2 border) x (height + 2 border) (CLR_SPLAT_BORDER), of which only the window's
   pixels are gathered. Without it the border is 0 and the grid is the window. */
#include "li.h"
#include "filter.h"
#ifdef CLR_FEATURE_AOVS
#include "feature_aovs.h"
#endif

/* Pixels from which a sample can reach a pixel: |offset| <= splat_reach in x and y. */
INLINE int splat_reach(__global const Camera* cam) {
    return (int)ceil(cam->filter_radius - 0.5f);
}

/* Pixels of border around the window whose samples are drawn too: splat_reach with Mitsuba's sample_border, else
   0 (Nori's film too places samples in the window only, whatever its camera's clip_window says for filter
   sampling). The host decides it (Renderer.splat_border) and builds the program with it. */
#ifndef CLR_SPLAT_BORDER
#define CLR_SPLAT_BORDER 0
#endif

/* Sample `index` of record pixel `pix` (in the grid with CLR_SPLAT_BORDER around the window) as a splatting film
   draws it: its position u inside the pixel and its radiance L; false for a NaN/Inf sample, which is dropped. */
INLINE bool splat_sample(SceneData* sd, __global const Camera* cam, uint pix, uint index, uint seed, float2* u,
                         vec3* L) {
    int b = CLR_SPLAT_BORDER;
    uint gw = cam->width + 2u * (uint)b;
    int px = (int)(pix % gw) - b, py = (int)(pix / gw) - b;
    Sampler smp;
    sampler_init(&smp, seed, pix, index);
    *u = next2d(&smp);
    float2 lens = cam->lens_radius > 0.0f ? next2d(&smp) : (float2)(0.5f, 0.5f);
    Ray ray = camera_ray_lens(cam, (float)px + u->x, (float)py + u->y, lens);
    *L = Li(sd, ray, &smp);
#ifdef CLRENDER_TEST_POISON
    if (index % 5u == 0u) L->x = NAN;
    else if (index % 7u == 0u) L->y = INFINITY;
#endif
    return all_finite(*L);
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
    int reach = splat_reach(cam);
    uint k = 2u * (uint)reach + 1u;
    size_t first = (size_t)(pix - rec_base) * spp;
    for (uint s = 0u; s < spp; ++s) {
        float2 u;
        vec3 L;
        bool ok = splat_sample(&sd, cam, pix, sample_offset + s, seed, &u, &L);
        records[first + s] = ok ? vf4(L, 1.0f) : (float4)(0.0f);
        __global float* wt = weights + (first + s) * 2u * k;
        for (int t = -reach; t <= reach; ++t) {
            wt[reach + t] = ok ? filter_eval_1d(cam, (float)t + 0.5f - u.x) : 0.0f;
            wt[k + reach + t] = ok ? filter_eval_1d(cam, (float)t + 0.5f - u.y) : 0.0f;
        }
    }
}

/* Pixels pixel_offset .. + pixel_count: the pass's records of every neighbour within reach (the records hold
   record pixels rec_first .. rec_stop - 1 of the grid with CLR_SPLAT_BORDER, record pixel p at (p - rec_base) * spp)
   added to the film's sums (SPLAT_FILM_ARGS, clrender/device/layout.py): acc0 (sum w L, sum w), acc1 (sum (w L)^2, own samples), acc2 (sum w^2 L, sum w^2: with acc1 the variance of the ratio), bad. */
__kernel void splat_gather(__global const Camera* cam, __global const float4* records, __global const float* weights,
                           uint rec_base, uint rec_first, uint rec_stop, SPLAT_FILM_ARGS, uint pixel_offset,
                           uint pixel_count, uint sample_offset, uint spp, uint seed) {
    uint gid = get_global_id(0);
    if (gid >= pixel_count) return;
    uint q = pixel_offset + gid;
    int w = (int)cam->width, h = (int)cam->height;
    int qx = (int)(q % cam->width), qy = (int)(q / cam->width);
    int reach = splat_reach(cam), b = CLR_SPLAT_BORDER;
    int gw = w + 2 * b;
    uint rq = (uint)((qy + b) * gw + qx + b);   /* this pixel's own samples' record pixel */
    uint k = 2u * (uint)reach + 1u;
    vec3 swl = v3s(0.0f), swl2 = v3s(0.0f), sw2l = v3s(0.0f);
    float sw = 0.0f, sw2 = 0.0f;
    uint own = 0u;
    for (int y = max(qy - reach, -b); y <= min(qy + reach, h - 1 + b); ++y) {
        for (int x = max(qx - reach, -b); x <= min(qx + reach, w - 1 + b); ++x) {
            uint p = (uint)((y + b) * gw + x + b);
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
                if (p == rq) own += r.w > 0.0f ? 1u : 0u;
            }
        }
    }
    float4 a0 = acc0[q], a1 = acc1[q], a2 = acc2[q];
    acc0[q] = vf4(vadd(vxyz(a0), swl), a0.w + sw);
    acc1[q] = vf4(vadd(vxyz(a1), swl2), a1.w + (float)own);
    acc2[q] = vf4(vadd(vxyz(a2), sw2l), a2.w + sw2);
    if (rq >= rec_first && rq < rec_stop) bad[q] += spp - own;
}

/* Adaptive sampling's splatting film (clrender/executors.py SplatExecutor, its store). Pixels whose sample counts
   differ cannot pour their samples into shared sums: a pixel with 16 times the samples of its neighbour would
   weigh 16 times as much in the pixels between them, and an edge there would move. So each pixel keeps its own
   samples' splats apart: toward the pixel at offset (tx, ty), with w = f(tx + 1/2 - u.x) f(ty + 1/2 - u.y), the
   entries e = SPLAT_STORE_ENTRIES ((2 reach + 1)^2 pix + (2 reach + 1) (ty + reach) + tx + reach) of the store
   hold (sum of w L, sum of w) at e, (sum of w^2 L, sum of w^2) at e + 1 and (sum of w^2 L^2, 0) at e + 2 (what
   the film's variance takes, kept per splat: a variance made from each pixel's own spread and the filter's mean
   squared weight was 500 times too large beside the Cornell box's light, whose bright samples lie on the far side
   of their pixel and weigh little); counts[pix] = (its samples, dropped ones). splat_resolve weighs each pixel's
   splats by 1 / its samples, which with equal counts is the uniform splatting film's sums. A call's splats are
   summed in private memory and added to the store once (CLR_SPLAT_K = 2 reach + 1, set by the host), so a pixel's
   sums depend only on its own samples and the spans it got them in, never on which other pixels share a launch.
   The store holds the window's pixels only (CLR_SPLAT_BORDER 0): a film with sample_border renders adaptively by
   sampling the filter (clrender/renderer.py render_adaptive). */
#ifndef CLR_SPLAT_K
#define CLR_SPLAT_K 5
#endif
INLINE void store_pixel(SceneData* sd, __global const Camera* cam, __global float4* store, __global uint2* counts,
                        uint pix, uint first, uint count, uint seed) {
    int reach = splat_reach(cam);
    int k = 2 * reach + 1;   /* == CLR_SPLAT_K */
    float4 acc[SPLAT_STORE_ENTRIES * CLR_SPLAT_K * CLR_SPLAT_K];
    for (int i = 0; i < SPLAT_STORE_ENTRIES * k * k; ++i) acc[i] = (float4)(0.0f);
    uint nbad = 0u;
    for (uint s = 0u; s < count; ++s) {
        float2 u;
        vec3 L;
        if (!splat_sample(sd, cam, pix, first + s, seed, &u, &L)) { nbad += 1u; continue; }
        vec3 L2 = vmul(L, L);
        float wx[CLR_SPLAT_K];
        for (int t = 0; t < k; ++t) wx[t] = filter_eval_1d(cam, (float)(t - reach) + 0.5f - u.x);
        for (int ty = 0; ty < k; ++ty) {
            float wy = filter_eval_1d(cam, (float)(ty - reach) + 0.5f - u.y);
            for (int tx = 0; tx < k; ++tx) {
                float w = wy * wx[tx], w2 = w * w;
                __private float4* a = acc + SPLAT_STORE_ENTRIES * (ty * k + tx);
                a[0] += vf4(vscale(L, w), w);
                a[1] += vf4(vscale(L, w2), w2);
                a[2] += vf4(vscale(L2, w2), 0.0f);
            }
        }
    }
    if (count > nbad) {
        __global float4* st = store + (size_t)pix * (size_t)(SPLAT_STORE_ENTRIES * k * k);
        for (int i = 0; i < SPLAT_STORE_ENTRIES * k * k; ++i) st[i] += acc[i];
    }
    counts[pix] += (uint2)(count, nbad);
}

/* Samples sample_offset .. + spp - 1 of pixels pixel_offset .. + pixel_count - 1 into the store. */
__kernel void store_pass(SCENE_ARGS, __global const Camera* cam, __global float4* store, __global uint2* counts,
                         uint pixel_offset, uint pixel_count, uint sample_offset, uint spp, uint seed) {
    uint gid = get_global_id(0);
    if (gid >= pixel_count) return;
    SCENE_INIT(sd);
    store_pixel(&sd, cam, store, counts, pixel_offset + gid, sample_offset, spp, seed);
}

/* Entry i of pixel_list[pixel_offset ..] with its own samples spans[i] = (first, count) (render.cl render_spans'
   rounds), each pixel at most once per launch. */
__kernel void store_spans(SCENE_ARGS, __global const Camera* cam, __global float4* store, __global uint2* counts,
                          __global const uint* pixel_list, __global const uint2* spans, uint pixel_offset,
                          uint pixel_count, uint seed) {
    uint gid = get_global_id(0);
    if (gid >= pixel_count) return;
    SCENE_INIT(sd);
    uint2 span = spans[pixel_offset + gid];
    store_pixel(&sd, cam, store, counts, pixel_list[pixel_offset + gid], span.x, span.y, seed);
}

/* The film's sums (SPLAT_FILM_ARGS, overwritten) of pixels pixel_offset .. + pixel_count - 1 from the store: each
   splat toward this pixel from a pixel p within reach weighed by 1 / n_p (its samples): acc0 = (sum of w L / n_p,
   sum of w / n_p), acc1 = (sum of w^2 L^2 / n_p^2, this pixel's finite samples), acc2 = (sum of w^2 L / n_p^2, sum
   of w^2 / n_p^2): the uniform film's sums with each sample's weight w / n_p (Film._splat_variance). Without
   `normalise` (every pixel has the same count: adaptive sampling's switch to a uniform render) the uniform film's
   very sums, to which render_records and splat_gather can add. */
__kernel void splat_resolve(__global const Camera* cam, __global const float4* store, __global const uint2* counts,
                            SPLAT_FILM_ARGS, uint pixel_offset, uint pixel_count, uint normalise) {
    uint gid = get_global_id(0);
    if (gid >= pixel_count) return;
    uint q = pixel_offset + gid;
    int w = (int)cam->width, h = (int)cam->height;
    int qx = (int)(q % cam->width), qy = (int)(q / cam->width);
    int reach = splat_reach(cam);
    int k = 2 * reach + 1;
    float4 s0 = (float4)(0.0f), s1 = (float4)(0.0f), s2 = (float4)(0.0f);
    for (int ty = -reach; ty <= reach; ++ty) {
        int y = qy - ty;
        if (y < 0 || y >= h) continue;
        for (int tx = -reach; tx <= reach; ++tx) {
            int x = qx - tx;
            if (x < 0 || x >= w) continue;
            size_t p = (size_t)(y * w + x);
            uint n = counts[p].x;
            if (n == 0u) continue;
            float inv = normalise ? 1.0f / (float)n : 1.0f;
            __global const float4* e =
                store + SPLAT_STORE_ENTRIES * (p * (size_t)(k * k) + (size_t)((ty + reach) * k + tx + reach));
            s0 += e[0] * inv;
            s1 += e[1] * (inv * inv);
            s2 += e[2] * (inv * inv);
        }
    }
    uint2 c = counts[q];
    acc0[q] = s0;
    acc1[q] = (float4)(s2.xyz, (float)(c.x - c.y));
    acc2[q] = s1;
    bad[q] = c.y;
}
