/* The wavefront driver of the path integrators (path_mats, path_ems, path_mis, Mitsuba's path, volpath, volpathmis,
   prb): the stages of kernels/integrators/path.h as kernels of their own, over queues of the paths that need them
   (pbrt-v4's shape; clrender/wavefront.py launches them). A wave holds `k` consecutive samples of each pixel of a
   range; its PathStates, Samplers and Hits live in device buffers indexed by slot = pixel * k + sample. Queues are
   slot lists filled with atomic counters (their order varies from run to run; each path's arithmetic does not).
   The random numbers are the megakernel's, keyed by (seed, pixel, sample, dimension), and each pixel's samples are
   summed in the megakernel's order (wf_finish, wf_flush): both drivers give the same image up to float rounding. */
/* the stage kernels' forms of the searches and the sampler (kernels/math.h, rng.h): no per-item loop, no switch */
#define CLR_WAVEFRONT_STAGES 1
#include "li.h"
#include "filter.h"
#ifdef CLR_FEATURE_AOVS
#include "feature_aovs.h"
#endif

#ifndef CLR_PATH_STAGES
#error "the wavefront driver runs the path integrators only (kernels/integrators/path_loop.h)"
#endif

/* What a path needs next, in the flags the camera and shade stages write (wf_compact reads them). */
#define QUEUE_TRACE 1u
#define QUEUE_SHADOW 2u

/* Per-slot state (PathState, Sampler, Hit) as 32-bit words: word j of slot s of a struct of `words` words at
   col[WF_INDEX(j, words, stride, slot)]: array-of-structures by default (a path's state is a few neighbouring cache
   lines), structure-of-arrays with -DWF_SOA (stride: the number of slots), measured in benchmarks/README.md. The
   copy loops have a constant trip count and are unrolled whole. `first`, `count`: a part of the struct, in words. */
#define WF_WORDS(T) ((uint)(sizeof(T) / 4u))
#define WF_WORD_OF(base, member) ((uint)(((char*)&(member) - (char*)&(base)) / 4))
#ifdef WF_SOA
#define WF_INDEX(j, words, stride, slot) ((j) * (stride) + (slot))
#else
#define WF_INDEX(j, words, stride, slot) ((size_t)(slot) * (words) + (j))
#endif
#define WF_GET(col, T, stride, slot, dst, first, count) do { \
        uint* wf_w_ = (uint*)(dst); \
        _Pragma("unroll") for (uint wf_j_ = 0u; wf_j_ < (count); ++wf_j_) \
            wf_w_[wf_j_] = (col)[WF_INDEX((first) + wf_j_, WF_WORDS(T), stride, slot)]; \
    } while (0)
#define WF_LOAD(T, col, stride, slot, dst) WF_GET(col, T, stride, slot, dst, 0u, WF_WORDS(T))
#define WF_STORE(T, col, stride, slot, src) do { \
        const uint* wf_w_ = (const uint*)(src); \
        _Pragma("unroll") for (uint wf_j_ = 0u; wf_j_ < WF_WORDS(T); ++wf_j_) \
            (col)[WF_INDEX(wf_j_, WF_WORDS(T), stride, slot)] = wf_w_[wf_j_]; \
    } while (0)

/* The pixel of launch index i: i itself over a range of pixels, or pixel_list[i] when the launch runs over a list
   (adaptive sampling's rounds; `listed` != 0). */
inline uint listed_pixel(__global const uint* pixel_list, uint listed, uint i) {
    return listed ? pixel_list[i] : i;
}

#ifndef WF_LANES
#define WF_LANES 1   /* paths per work-item of the shade stage */
#endif

/* The sizes the host allocates per slot: PathState, Sampler, Hit (the kernels' own layout, so nothing on the host
   spells it out), and the paths a shade work-item takes (WF_LANES). */
__kernel void wf_sizes(__global uint* out) {
    out[0] = (uint)sizeof(PathState);
    out[1] = (uint)sizeof(Sampler);
    out[2] = (uint)sizeof(Hit);
    out[3] = WF_LANES;
}

/* Camera stage: the camera sample of every slot (sample_offset + slot % k of pixel pixel_offset + slot / k, or of
   the list's entry at that index), its filter weight in wt[slot].x (wt[slot].y = 0 for a sample outside the window:
   it counts, but adds nothing) and flags[slot] = QUEUE_TRACE when the path's first segment is to be traced
   (wf_compact queues it). */
__kernel void wf_camera(SCENE_ARGS, __global const Camera* cam, __global const float* filter_cdf,
                        __global uint* paths, __global uint* samplers, uint stride, __global float2* wt,
                        __global uint* flags, __global const uint* pixel_list, uint listed,
                        uint pixel_offset, uint n_slots, uint k, uint sample_offset, uint seed) {
    uint slot = get_global_id(0);
    if (slot >= n_slots) return;
    SCENE_INIT(sd);
    uint pix = listed_pixel(pixel_list, listed, pixel_offset + slot / k);
    Sampler smp;
    sampler_init(&smp, seed, pix, sample_offset + slot % k);
    float w = 0.0f;
    Ray ray;
    PathState ps;
    if (camera_sample(cam, filter_cdf, pix % cam->width, pix / cam->width, &smp, &w, &ray)) {
        path_begin(&sd, &ps, ray);
        wt[slot] = (float2)(w, 1.0f);
    } else {
        ps.alive = 0u;
        wt[slot] = (float2)(0.0f, 0.0f);
    }
    WF_STORE(PathState, paths, stride, slot, &ps);
    WF_STORE(Sampler, samplers, stride, slot, &smp);
    flags[slot] = ps.alive ? QUEUE_TRACE : 0u;
}

/* Trace stage: the closest hit of each queued path's segment (t < 0: it hit nothing). */
__kernel void wf_trace(SCENE_ARGS, __global const uint* paths, __global uint* hits, uint stride,
                       __global const uint* queue, uint n) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    uint slot = queue[i];
    PathState ps;
    Ray r;
    WF_GET(paths, PathState, stride, slot, &r, WF_WORD_OF(ps, ps.ray), WF_WORDS(Ray));
    Hit h;
    if (!scene_trace(&sd, &r, &h)) h.t = -1.0f;
    WF_STORE(Hit, hits, stride, slot, &h);
}

/* Shade stage: surface reconstruction, emission and its MIS weight, the emitter sample (a shadow ray to trace:
   QUEUE_SHADOW in flags[i]), roulette and the BSDF sample (the next segment to trace: QUEUE_TRACE). */
#if WF_LANES > 1
/* WF_LANES paths per work-item (opt-in, measured in benchmarks/README.md, "third step"), in three loops: their state
   copied into private arrays, one row per word with the lanes side by side; the shading over the lanes, a loop that
   LLVM's loop vectoriser widens in PoCL's first -O3 round, before the SLP vectoriser of that round can pack pairs of
   a path's scalars into <2 x float> values (which keep PoCL's own work-item loop scalar); and the state copied
   back. Lanes past n repeat the last path and are not copied back. Needs -DCLR_VEC3_PASS_IN_MEMORY (x86-64 passes a
   12-byte vec3 as a <2 x float> piece, which the vectoriser refuses). */
#define WF_LSTRIDE (2 * WF_LANES)   /* rows two vectors apart: no dependence between rows for the vectoriser to check */
#define WF_LANE_GET(T, arr, lane, dst) do { \
        uint* wf_w_ = (uint*)(dst); \
        _Pragma("unroll") for (uint wf_j_ = 0u; wf_j_ < WF_WORDS(T); ++wf_j_) \
            wf_w_[wf_j_] = (arr)[wf_j_ * WF_LSTRIDE + (lane)]; \
    } while (0)
#define WF_LANE_PUT(T, arr, lane, src) do { \
        const uint* wf_w_ = (const uint*)(src); \
        _Pragma("unroll") for (uint wf_j_ = 0u; wf_j_ < WF_WORDS(T); ++wf_j_) \
            (arr)[wf_j_ * WF_LSTRIDE + (lane)] = wf_w_[wf_j_]; \
    } while (0)
/* word by word between a slot of a per-slot buffer and a lane of a private array */
#define WF_TO_LANE(T, arr, lane, col, stride, slot) \
    _Pragma("unroll") for (uint wf_j_ = 0u; wf_j_ < WF_WORDS(T); ++wf_j_) \
        (arr)[wf_j_ * WF_LSTRIDE + (lane)] = (col)[WF_INDEX(wf_j_, WF_WORDS(T), stride, slot)]
#define WF_FROM_LANE(T, arr, lane, col, stride, slot) \
    _Pragma("unroll") for (uint wf_j_ = 0u; wf_j_ < WF_WORDS(T); ++wf_j_) \
        (col)[WF_INDEX(wf_j_, WF_WORDS(T), stride, slot)] = (arr)[wf_j_ * WF_LSTRIDE + (lane)]
__kernel void wf_shade(SCENE_ARGS, __global uint* paths, __global uint* samplers, __global const uint* hits,
                       uint stride, __global const uint* queue, uint n, __global uint* flags) {
    uint base = get_global_id(0) * WF_LANES;
    if (base >= n) return;
    SCENE_INIT(sd);
    uint ps_w[WF_WORDS(PathState) * WF_LSTRIDE], smp_w[WF_WORDS(Sampler) * WF_LSTRIDE];
    uint h_w[WF_WORDS(Hit) * WF_LSTRIDE], flag_w[WF_LANES];
    for (uint lane = 0u; lane < WF_LANES; ++lane) {
        uint slot = queue[min(base + lane, n - 1u)];
        WF_TO_LANE(PathState, ps_w, lane, paths, stride, slot);
        WF_TO_LANE(Sampler, smp_w, lane, samplers, stride, slot);
        WF_TO_LANE(Hit, h_w, lane, hits, stride, slot);
    }
#pragma clang loop vectorize(enable) vectorize_width(WF_LANES) interleave_count(1)
    for (uint lane = 0u; lane < WF_LANES; ++lane) {
        PathState ps;
        Sampler smp;
        Hit h;
        WF_LANE_GET(PathState, ps_w, lane, &ps);
        WF_LANE_GET(Sampler, smp_w, lane, &smp);
        WF_LANE_GET(Hit, h_w, lane, &h);
        path_vertex(&sd, &ps, h.t >= 0.0f, &h, &smp);
        WF_LANE_PUT(PathState, ps_w, lane, &ps);
        WF_LANE_PUT(Sampler, smp_w, lane, &smp);
        flag_w[lane] = (ps.alive ? QUEUE_TRACE : 0u) | (ps.shadow_pending ? QUEUE_SHADOW : 0u);
    }
    for (uint lane = 0u; lane < WF_LANES && base + lane < n; ++lane) {
        uint slot = queue[base + lane];
        WF_FROM_LANE(PathState, ps_w, lane, paths, stride, slot);
        WF_FROM_LANE(Sampler, smp_w, lane, samplers, stride, slot);
        flags[base + lane] = flag_w[lane];
    }
}
#else
__kernel void wf_shade(SCENE_ARGS, __global uint* paths, __global uint* samplers, __global const uint* hits,
                       uint stride, __global const uint* queue, uint n, __global uint* flags) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    uint slot = queue[i];
    PathState ps;
    Sampler smp;
    Hit h;
    WF_LOAD(PathState, paths, stride, slot, &ps);
    WF_LOAD(Sampler, samplers, stride, slot, &smp);
    WF_LOAD(Hit, hits, stride, slot, &h);
    path_vertex(&sd, &ps, h.t >= 0.0f, &h, &smp);
    WF_STORE(PathState, paths, stride, slot, &ps);
    WF_STORE(Sampler, samplers, stride, slot, &smp);
    flags[i] = (ps.alive ? QUEUE_TRACE : 0u) | (ps.shadow_pending ? QUEUE_SHADOW : 0u);
}
#endif

/* The queues of the next stages from the flags the camera or shade stage left, one per launch index i (the
   slot is i itself after the camera stage, queue[i] after a shade stage): the paths to trace in next_queue
   (counts[0]), the shadow rays in shadow_queue (counts[1]). A kernel of its own so that the stages themselves hold
   no atomic (a call PoCL's vectoriser cannot widen); it is a few instructions per path. */
__kernel void wf_compact(__global const uint* flags, __global const uint* queue, uint identity, uint n,
                         __global uint* next_queue, __global uint* shadow_queue, __global uint* counts) {
    uint i = get_global_id(0);
    if (i >= n) return;
    uint f = flags[i];
    uint slot = identity ? i : queue[i];
    if (f & QUEUE_TRACE) next_queue[atomic_inc(&counts[0])] = slot;
    if (f & QUEUE_SHADOW) shadow_queue[atomic_inc(&counts[1])] = slot;
}

/* Shadow stage: the pending emitter samples count where their shadow rays reach the light. */
__kernel void wf_shadow(SCENE_ARGS, __global uint* paths, uint stride, __global const uint* queue, uint n) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    uint slot = queue[i];
    PathState ps;
    WF_LOAD(PathState, paths, stride, slot, &ps);
    path_shadow_done(&ps, shadow_occluded(&sd, &ps.shadow));
    WF_STORE(PathState, paths, stride, slot, &ps);
}

/* Finish stage: each pixel's k finished samples added to its sums of this pass, in sample order, as render_pass adds
   them: sum0 = (sum wL, sum w), sum1 = (sum (wL)^2, -), nbad = samples dropped for being NaN/Inf. */
__kernel void wf_finish(SCENE_ARGS, __global const uint* paths, uint stride, __global const float2* wt,
                        __global float4* sum0, __global float4* sum1, __global uint* nbad, uint n_pixels, uint k) {
    uint gid = get_global_id(0);
    if (gid >= n_pixels) return;
    SCENE_INIT(sd);
    vec3 swl = vrow(sum0[gid]), swl2 = vrow(sum1[gid]);
    float sw = sum0[gid].w;
    uint bad = nbad[gid];
    for (uint j = 0u; j < k; ++j) {
        uint slot = gid * k + j;
        float2 w = wt[slot];
        if (w.y == 0.0f) continue;
        PathState ps;
        WF_LOAD(PathState, paths, stride, slot, &ps);
        vec3 L = path_result(&sd, &ps);
        if (!all_finite(L) || !isfinite(w.x)) { bad += 1u; continue; }
        vec3 wl = vscale(L, w.x);
        swl = vadd(swl, wl);
        swl2 = vadd(swl2, vmul(wl, wl));
        sw += w.x;
    }
    sum0[gid] = vf4(swl, sw);
    sum1[gid] = vf4(swl2, 0.0f);
    nbad[gid] = bad;
}

/* The pass's sums into the film accumulators (FILM_ARGS, clrender/device/layout.py FILM_ACCUMULATORS; rays is not
   counted by this driver), as render_pass adds them; the sums start again from zero. */
__kernel void wf_flush(__global float4* sum0, __global float4* sum1, __global uint* nbad, FILM_ARGS,
                       __global const uint* pixel_list, uint listed, uint pixel_offset, uint n_pixels, uint spp) {
    uint gid = get_global_id(0);
    if (gid >= n_pixels) return;
    uint pix = listed_pixel(pixel_list, listed, pixel_offset + gid);
    float4 s0 = sum0[gid], s1 = sum1[gid];
    uint nb = nbad[gid];
    float4 a0 = acc0[pix], a1 = acc1[pix];
    acc0[pix] = vf4(vadd(vxyz(a0), vxyz(s0)), a0.w + s0.w);
    acc1[pix] = vf4(vadd(vxyz(a1), vxyz(s1)), a1.w + (float)(spp - nb));
    bad[pix] += nb;
    sum0[gid] = (float4)(0.0f);
    sum1[gid] = (float4)(0.0f);
    nbad[gid] = 0u;
}
