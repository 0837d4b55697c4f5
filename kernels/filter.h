/* Reconstruction filters, applied by filter importance sampling (a splatting film evaluates the same profile:
   kernels/splat.cl): each camera sample is placed at an offset
   (dx, dy) from its pixel's centre drawn from a tabulated density p(x)p(y) ~ |f(x)||f(y)|, and carries the
   weight f(dx)f(dy) / (p(dx)p(dy)). The film divides sum(w L) by sum(w), so a pixel converges to
   integral f L / integral f: the same limit as Nori's splatting of uniformly placed samples, except near the
   image border, where Nori's samples stop at the border and ours keep to the filter's footprint. */
#ifndef CLRENDER_FILTER_H
#define CLRENDER_FILTER_H
#include "math.h"
#include "rng.h"
#include "camera.h"
#include "gen/rfilter_dispatch.h"

/* The filter's profile f(x) (filter_profile_eval: generated from the registered rfilter plugins,
   kernels/filters/<prefix>.h), zero outside its radius. */
INLINE float filter_eval_1d(__global const Camera* cam, float x) {
    if (fabs(x) > cam->filter_radius) return 0.0f;
    return filter_profile_eval(cam, x);
}

/* The offset for u inside table bin `lo` (cdf[lo] <= u < cdf[lo+1]) and its density. */
INLINE float filter_in_bin(__global const Camera* cam, __global const float* cdf, uint lo, float u, float* pdf) {
    uint n = cam->filter_bins;
    float c0 = cdf[lo], c1 = cdf[lo + 1u];
    float pm = c1 - c0;
    float frac = pm > 0.0f ? (u - c0) / pm : 0.5f;
    frac = clampf(frac, 0.0f, 0.99999994f);
    float r = cam->filter_radius;
    float width = 2.0f * r / (float)n;
    *pdf = pm / width;
    return -r + ((float)lo + frac) * width;
}

/* Draw x in [-r, r] from the piecewise-constant table (cdf has bins+1 entries, cdf[0]=0, cdf[bins]=1).
   Returns x; *pdf receives its density. */
INLINE float filter_sample_1d(__global const Camera* cam, __global const float* cdf, float u, float* pdf) {
    uint n = cam->filter_bins;
#if defined(CLR_SEARCH_STEPS) && defined(CLR_WAVEFRONT_STAGES)
    return filter_in_bin(cam, cdf, table_count_le(cdf, n, u) - 1u, u, pdf);   /* cdf[0] = 0 <= u: at least 1 */
#else
    uint lo = 0u, hi = n; /* find the bin i with cdf[i] <= u < cdf[i+1] */
    while (hi - lo > 1u) {
        uint mid = (lo + hi) >> 1;
        if (cdf[mid] <= u) lo = mid; else hi = mid;
    }
    return filter_in_bin(cam, cdf, lo, u, pdf);
#endif
}

/* filter_sample_1d for a table followed by its guide (clrender/filters/filter.py, with_guide): the same bin,
   found from guide[floor(u * bins)] in about one step instead of a bisection. */
INLINE float filter_sample_1d_guided(__global const Camera* cam, __global const float* cdf, float u, float* pdf) {
#if defined(CLR_SEARCH_STEPS) && defined(CLR_WAVEFRONT_STAGES)
    return filter_sample_1d(cam, cdf, u, pdf);   /* the same bin, in fixed steps (no per-item loop) */
#else
    uint n = cam->filter_bins;
    uint k = (uint)(u * (float)n);
    k = k < n ? k : n - 1u;
    uint lo = (uint)cdf[n + 1u + k];
    while (lo > 0u && cdf[lo] > u) --lo;              /* only if u * n rounded up */
    while (lo + 1u < n && cdf[lo + 1u] <= u) ++lo;
    return filter_in_bin(cam, cdf, lo, u, pdf);
#endif
}

/* f(dx) f(dy) / (p(dx) p(dy)): the weight of an offset drawn with densities px, py. */
INLINE float filter_weight(__global const Camera* cam, float dx, float px, float dy, float py) {
    if (!(px > 0.0f && py > 0.0f)) return 0.0f;
    return (filter_eval_1d(cam, dx) / px) * (filter_eval_1d(cam, dy) / py);
}

/* An offset from the pixel centre and the sample's filter weight. */
INLINE float2 filter_sample(__global const Camera* cam, __global const float* cdf, float2 u, float* weight) {
    float px, py;
    float dx = filter_sample_1d(cam, cdf, u.x, &px);
    float dy = filter_sample_1d(cam, cdf, u.y, &py);
    *weight = filter_weight(cam, dx, px, dy, py);
    return (float2)(dx, dy);
}

/* filter_sample for a table with its guide (what the renderer uploads): the same offsets and weights. */
INLINE float2 filter_sample_guided(__global const Camera* cam, __global const float* table, float2 u, float* weight) {
    float px, py;
    float dx = filter_sample_1d_guided(cam, table, u.x, &px);
    float dy = filter_sample_1d_guided(cam, table, u.y, &py);
    *weight = filter_weight(cam, dx, px, dy, py);
    return (float2)(dx, dy);
}

/* The camera sample of pixel (px, py): a film position drawn from the filter (its weight in *w), a lens sample
   where the camera has a lens, and the ray. False for a position outside the window (Mitsuba's
   sample_border=false): a sample of weight 0 that traces nothing. render.cl, wavefront.cl and
   benchmarks/profile_pass.cl share it, so every driver draws the same dimensions for the same ray. */
INLINE bool camera_sample(__global const Camera* cam, __global const float* filter_cdf, uint px, uint py,
                          Sampler* smp, float* w, Ray* ray) {
    float2 off = filter_sample_guided(cam, filter_cdf, next2d(smp), w);
    float sx = (float)px + 0.5f + off.x, sy = (float)py + 0.5f + off.y;
    if (cam->clip_window != 0u &&
        !(sx >= 0.0f && sy >= 0.0f && sx <= (float)cam->width && sy <= (float)cam->height)) {
        return false;
    }
    float2 lens = cam->lens_radius > 0.0f ? next2d(smp) : (float2)(0.5f, 0.5f);
    *ray = camera_ray_lens(cam, sx, sy, lens);
    return true;
}

#endif
