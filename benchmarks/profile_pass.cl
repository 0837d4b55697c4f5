/* Kernels of benchmarks/profile_pass.py: one path tracing pass recorded ray by ray, the recorded rays cast
   again on their own, and the pass without its integrator. Built over the render program's headers. */

/* The recording pass hands Li a pointer to this struct's first member, so scene.h's queries (whose argument
   is called sd) reach the record through BVH_RECORD (kernels/bvh_queries.h) without any change to them. */
typedef struct {
    SceneData sd;
    __global float4* rec;   /* per ray: (o, tmin), (d, tmax) */
    __global uint* kind;    /* per ray: 0 closest hit, 1 any hit */
    uint base, n, cap, dropped;
} RecordScene;

static inline void record_ray(const SceneData* sd, uint kind, float3 o, float3 d, float tmin, float tmax) {
    RecordScene* r = (RecordScene*)sd;
    if (r->n >= r->cap) { r->dropped += 1u; return; }
    uint i = r->base + r->n++;
    r->rec[2 * i] = (float4)(o, tmin);
    r->rec[2 * i + 1] = (float4)(d, tmax);
    r->kind[i] = kind;
}
#define BVH_RECORD(kind, o, d, tmin, tmax) record_ray(sd, kind, o, d, tmin, tmax)

#include "li.h"
#include "filter.h"

/* render_pass (render.cl) for one sample per pixel, recording every BVH query: pixel p's rays are rows
   p*cap .. p*cap + count[p] - 1, in the order the pass traced them. */
__kernel void record_pass(SCENE_ARGS, __global const Camera* cam, __global const float* filter_cdf,
                          __global float4* rec, __global uint* kind, __global uint2* count, uint cap,
                          uint sample, uint seed) {
    uint pix = get_global_id(0);
    if (pix >= cam->width * cam->height) return;
    RecordScene rs;
    {
        SCENE_INIT(sd);
        rs.sd = sd;
    }
    rs.rec = rec; rs.kind = kind; rs.base = pix * cap; rs.n = 0u; rs.cap = cap; rs.dropped = 0u;
    uint px = pix % cam->width, py = pix / cam->width;
    Sampler smp;
    sampler_init(&smp, seed, pix, sample);
    float w;
    float2 off = filter_sample_guided(cam, filter_cdf, next2d(&smp), &w);
    Ray ray = camera_ray(cam, (float)px + 0.5f + off.x, (float)py + 0.5f + off.y);
    Li(&rs.sd, ray, &smp);
    count[pix] = (uint2)(rs.n, rs.dropped);
}

/* From here on the queries are the plain functions again. */
#undef bvh_closest_hit
#undef bvh_any_hit

/* The recorded rays again, one work-item per pixel as in the pass, each pixel's rays in their order. hit_t
   gets the t of each ray's hit (closest, or the one that stopped an any-hit query; -1 for none), and the
   boxes-only build (BVH_PROFILE_BOXES_ONLY) casts with tmax = that t. */
__kernel void cast_rays(SCENE_ARGS, __global const float4* rec, __global const uint* kind,
                        __global const uint2* count, uint cap, uint n_pixels, __global float* hit_t,
                        __global float* out) {
    uint pix = get_global_id(0);
    if (pix >= n_pixels) return;
    SCENE_INIT(sd);
    float acc = 0.0f;
    uint n = count[pix].x;
    for (uint k = 0u; k < n; ++k) {
        uint i = pix * cap + k;
        float4 a = rec[2 * i], b = rec[2 * i + 1];
#ifdef BVH_PROFILE_BOXES_ONLY
        float t = hit_t[i];
        float tmax = t >= 0.0f ? t : b.w;
        Hit h;
        if (kind[i] == 0u) acc += bvh_closest_hit(sd.nodes, sd.prims, a.xyz, b.xyz, a.w, tmax, &h) ? 1.0f : 0.0f;
        else acc += bvh_any_hit(sd.nodes, sd.prims, a.xyz, b.xyz, a.w, tmax) ? 1.0f : 0.0f;
#else
        if (kind[i] == 0u) {
            Hit h;
            float t = bvh_closest_hit(sd.nodes, sd.prims, a.xyz, b.xyz, a.w, b.w, &h) ? h.t : -1.0f;
            hit_t[i] = t;
            acc += t;
        } else {
            Hit h;   /* the traversal itself, for the t of the hit that stopped it */
            bool o = BVH_TRAVERSE(sd.nodes, sd.prims, a.xyz, b.xyz, a.w, b.w, &h, true);
            hit_t[i] = o ? h.t : -1.0f;
            acc += o ? 1.0f : 0.0f;
        }
#endif
    }
    out[pix] = acc;
}

/* render_pass for one sample per pixel without Li: sampler, filter, camera ray and accumulation only. */
__kernel void setup_pass(__global const Camera* cam, __global const float* filter_cdf, __global float4* acc0,
                         __global float4* acc1, uint sample, uint seed) {
    uint pix = get_global_id(0);
    if (pix >= cam->width * cam->height) return;
    uint px = pix % cam->width, py = pix / cam->width;
    Sampler smp;
    sampler_init(&smp, seed, pix, sample);
    float w;
    float2 off = filter_sample_guided(cam, filter_cdf, next2d(&smp), &w);
    Ray ray = camera_ray(cam, (float)px + 0.5f + off.x, (float)py + 0.5f + off.y);
    float3 wl = (ray.d + ray.o * next1d(&smp)) * w;   /* keeps the sampling alive without tracing */
    float4 a0 = acc0[pix], a1 = acc1[pix];
    acc0[pix] = (float4)(a0.xyz + wl, a0.w + w);
    acc1[pix] = (float4)(a1.xyz + wl * wl, a1.w + 1.0f);
}
