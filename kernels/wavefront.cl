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

/* The pixel of launch index i: i itself over a range of pixels, or pixel_list[i] when the launch runs over a list
   (adaptive sampling's rounds; `listed` != 0). */
inline uint listed_pixel(__global const uint* pixel_list, uint listed, uint i) {
    return listed ? pixel_list[i] : i;
}

/* The sizes the host allocates per slot: PathState, Sampler, Hit (the kernels' own layout, so nothing on the host
   spells it out). */
__kernel void wf_sizes(__global uint* out) {
    out[0] = (uint)sizeof(PathState);
    out[1] = (uint)sizeof(Sampler);
    out[2] = (uint)sizeof(Hit);
}

/* Camera stage: the camera sample of every slot (sample_offset + slot % k of pixel pixel_offset + slot / k, or of
   the list's entry at that index), its filter weight in wt[slot].x (wt[slot].y = 0 for a sample outside the window:
   it counts, but adds nothing) and flags[slot] = QUEUE_TRACE when the path's first segment is to be traced
   (wf_compact queues it). */
__kernel void wf_camera(SCENE_ARGS, __global const Camera* cam, __global const float* filter_cdf,
                        __global PathState* paths, __global Sampler* samplers, __global float2* wt,
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
    paths[slot] = ps;
    samplers[slot] = smp;
    flags[slot] = ps.alive ? QUEUE_TRACE : 0u;
}

/* Trace stage: the closest hit of each queued path's segment (t < 0: it hit nothing). */
__kernel void wf_trace(SCENE_ARGS, __global const PathState* paths, __global Hit* hits, __global const uint* queue,
                       uint n) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    uint slot = queue[i];
    Ray r = paths[slot].ray;
    Hit h;
    if (!scene_trace(&sd, &r, &h)) h.t = -1.0f;
    hits[slot] = h;
}

/* Shade stage: surface reconstruction, emission and its MIS weight, the emitter sample (a shadow ray to trace:
   QUEUE_SHADOW in flags[i]), roulette and the BSDF sample (the next segment to trace: QUEUE_TRACE). */
__kernel void wf_shade(SCENE_ARGS, __global PathState* paths, __global Sampler* samplers, __global const Hit* hits,
                       __global const uint* queue, uint n, __global uint* flags) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    uint slot = queue[i];
    PathState ps = paths[slot];
    Sampler smp = samplers[slot];
    Hit h = hits[slot];
    path_vertex(&sd, &ps, h.t >= 0.0f, &h, &smp);
    paths[slot] = ps;
    samplers[slot] = smp;
    flags[i] = (ps.alive ? QUEUE_TRACE : 0u) | (ps.shadow_pending ? QUEUE_SHADOW : 0u);
}

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
__kernel void wf_shadow(SCENE_ARGS, __global PathState* paths, __global const uint* queue, uint n) {
    uint i = get_global_id(0);
    if (i >= n) return;
    SCENE_INIT(sd);
    uint slot = queue[i];
    PathState ps = paths[slot];
    path_shadow_done(&ps, shadow_occluded(&sd, &ps.shadow));
    paths[slot] = ps;
}

/* Finish stage: each pixel's k finished samples added to its sums of this pass, in sample order, as render_pass adds
   them: sum0 = (sum wL, sum w), sum1 = (sum (wL)^2, -), nbad = samples dropped for being NaN/Inf. */
__kernel void wf_finish(SCENE_ARGS, __global const PathState* paths, __global const float2* wt,
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
        PathState ps = paths[slot];
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
