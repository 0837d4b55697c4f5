/* Kernels of benchmarks/profile_pass.py: one path tracing pass recorded ray by ray, the recorded rays cast
   again on their own, and the pass without its integrator. Built over the render program's headers. */

#include "math.h"   /* vec3, for record_ray below (li.h includes it too, after it) */

/* The recording pass hands Li a pointer to this struct's first member, so scene.h's queries (whose argument
   is called sd) reach the record through BVH_RECORD (kernels/bvh_queries.h) without any change to them. */
typedef struct {
    SceneData sd;
    __global float4* rec;   /* per ray: (o, tmin), (d, tmax) */
    __global uint* kind;    /* per ray: 0 closest hit, 1 any hit */
    uint base, n, cap, dropped;
} RecordScene;

static inline void record_ray(const SceneData* sd, uint kind, vec3 o, vec3 d, float tmin, float tmax) {
    RecordScene* r = (RecordScene*)sd;
    if (r->n >= r->cap) { r->dropped += 1u; return; }
    uint i = r->base + r->n++;
    r->rec[2 * i] = vf4(o, tmin);
    r->rec[2 * i + 1] = vf4(d, tmax);
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
    Ray ray;
    if (camera_sample(cam, filter_cdf, px, py, &smp, &w, &ray)) Li(&rs.sd, ray, &smp);   /* render.cl's step */
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
#ifdef PROFILE_FIRST_ONLY
    n = min(n, 1u);   /* the camera rays alone */
#endif
    for (uint k = 0u; k < n; ++k) {
        uint i = pix * cap + k;
        float4 a = rec[2 * i], b = rec[2 * i + 1];
#ifdef BVH_PROFILE_BOXES_ONLY
        float t = hit_t[i];
        float tmax = t >= 0.0f ? t : b.w;
        Hit h;
        if (kind[i] == 0u) acc += bvh_closest_hit(sd.nodes, sd.prims, vxyz(a), vxyz(b), a.w, tmax, &h) ? 1.0f : 0.0f;
        else acc += bvh_any_hit(sd.nodes, sd.prims, vxyz(a), vxyz(b), a.w, tmax) ? 1.0f : 0.0f;
#else
        if (kind[i] == 0u) {
            Hit h;
            float t = bvh_closest_hit(sd.nodes, sd.prims, vxyz(a), vxyz(b), a.w, b.w, &h) ? h.t : -1.0f;
            hit_t[i] = t;
            acc += t;
        } else {
            Hit h;   /* the traversal itself, for the t of the hit that stopped it */
            bool o = BVH_TRAVERSE(sd.nodes, sd.prims, vxyz(a), vxyz(b), a.w, b.w, &h, true);
            hit_t[i] = o ? h.t : -1.0f;
            acc += o ? 1.0f : 0.0f;
        }
#endif
    }
    out[pix] = acc;
}

#ifdef BVH_COUNT_VISITS
/* cast_rays' queries, counting what each visits (bvh8.h BVH_VISIT): per pixel, summed over its rays of each
   kind, (nodes, leaves, leaf blocks, rays) for closest-hit rays in visits[2 pix] and any-hit ones in
   visits[2 pix + 1]. */
__kernel void count_visits(SCENE_ARGS, __global const float4* rec, __global const uint* kind,
                           __global const uint2* count, uint cap, uint n_pixels, __global uint4* visits) {
    uint pix = get_global_id(0);
    if (pix >= n_pixels) return;
    SCENE_INIT(sd);
    uint4 v[2] = {(uint4)(0u), (uint4)(0u)};
    for (uint k = 0u; k < count[pix].x; ++k) {
        uint i = pix * cap + k;
        float4 a = rec[2 * i], b = rec[2 * i + 1];
        uint any = kind[i] == 0u ? 0u : 1u;
        Hit h;
        BVH_TRAVERSE(sd.nodes, sd.prims, vxyz(a), vxyz(b), a.w, b.w, &h, any != 0u);
        v[any] += (uint4)(h.nodes, h.leaves, h.blocks, 1u);
    }
    visits[2 * pix] = v[0];
    visits[2 * pix + 1] = v[1];
}
#endif

#ifdef PROFILE_PACKETS
/* The recorded rays as packets of 8: the k-th ray of 8 neighbouring pixels (the same bounce of 8 paths, as a
   packet integrator would trace them), one ray per float8 lane, through the 8-wide nodes one child at a time
   (Embree's packet traversal without its single-ray fallback). Closest-hit and any-hit lanes mix; an any-hit
   lane retires at its first hit. hit_t gets what cast_rays writes, for checking. Benchmark only. */
#define PK_LEAF_FIRST(ref) ((ref) & ((1u << BVH4_COUNT_SHIFT) - 1u))
#define PK_LEAF_COUNT(ref) ((((ref) >> BVH4_COUNT_SHIFT) & (BVH4_MAX_LEAF_COUNT - 1u)) + 1u)
#define PK_STACK 160

static inline float8 pk_abs(float8 x) { return x < 0.0f ? -x : x; }
static inline float8 pk_max(float8 a, float8 b) { return a > b ? a : b; }
static inline float8 pk_min(float8 a, float8 b) { return a < b ? a : b; }
static inline float8 pk_pick(float8 x, float8 y, float8 z, int8 k) { return k == 0 ? x : (k == 1 ? y : z); }

__kernel void cast_packets(SCENE_ARGS, __global const float4* rec, __global const uint* kind,
                           __global const uint2* count, uint cap, uint n_pixels, __global float* hit_t,
                           __global float* out) {
    uint g = get_global_id(0);
    if (8u * g >= n_pixels) return;
    SCENE_INIT(sd);
    __global const float8* rows = (__global const float8*)sd.nodes;
    __global const float* words = (__global const float*)sd.prims;
    uint cnt[8];
    uint maxc = 0u;
    for (uint l = 0u; l < 8u; ++l) {
        uint pix = 8u * g + l;
        cnt[l] = pix < n_pixels ? count[pix].x : 0u;
        maxc = max(maxc, cnt[l]);
    }
#ifdef PROFILE_FIRST_ONLY
    maxc = min(maxc, 1u);
#endif
    float acc = 0.0f;
    uint stack[PK_STACK];
    float8 stack_t[PK_STACK];
    for (uint k = 0u; k < maxc; ++k) {
        float ox[8], oy[8], oz[8], dx[8], dy[8], dz[8], t0[8], t1[8];
        int act[8], anyh[8];
        for (uint l = 0u; l < 8u; ++l) {
            uint pix = 8u * g + l;
            uint i = (pix < n_pixels ? pix : 0u) * cap + k;
            float4 a = rec[2 * i], b = rec[2 * i + 1];
            ox[l] = a.x; oy[l] = a.y; oz[l] = a.z; t0[l] = a.w;
            dx[l] = b.x; dy[l] = b.y; dz[l] = b.z; t1[l] = b.w;
            act[l] = k < cnt[l] ? -1 : 0;
            anyh[l] = (k < cnt[l] && kind[i] != 0u) ? -1 : 0;
        }
        float8 Ox = vload8(0, ox), Oy = vload8(0, oy), Oz = vload8(0, oz);
        float8 Dx = vload8(0, dx), Dy = vload8(0, dy), Dz = vload8(0, dz);
        float8 tmin = vload8(0, t0), T = vload8(0, t1);
        int8 live = vload8(0, act), shadow = vload8(0, anyh), hit = (int8)(0);
        float8 big = (float8)(1e30f);
        float8 Ix = pk_abs(Dx) > 1e-30f ? 1.0f / Dx : (Dx < 0.0f ? -big : big);
        float8 Iy = pk_abs(Dy) > 1e-30f ? 1.0f / Dy : (Dy < 0.0f ? -big : big);
        float8 Iz = pk_abs(Dz) > 1e-30f ? 1.0f / Dz : (Dz < 0.0f ? -big : big);
        int8 negx = Ix < 0.0f, negy = Iy < 0.0f, negz = Iz < 0.0f;
        /* the watertight test's ray space per lane */
        float8 ax = pk_abs(Dx), ay = pk_abs(Dy), az = pk_abs(Dz);
        int8 kz = ax > ay ? (ax > az ? (int8)(0) : (int8)(2)) : (ay > az ? (int8)(1) : (int8)(2));
        int8 kx = kz == 2 ? (int8)(0) : kz + 1;
        int8 ky = kx == 2 ? (int8)(0) : kx + 1;
        float8 okx = pk_pick(Ox, Oy, Oz, kx), oky = pk_pick(Ox, Oy, Oz, ky), okz = pk_pick(Ox, Oy, Oz, kz);
        float8 Sz = 1.0f / pk_pick(Dx, Dy, Dz, kz);
        float8 Sx = pk_pick(Dx, Dy, Dz, kx) * Sz, Sy = pk_pick(Dx, Dy, Dz, ky) * Sz;
        stack[0] = 0u;                      /* the root */
        stack_t[0] = tmin;
        int sp = 1;
        while (sp > 0) {
            --sp;
            uint cur = stack[sp];
            int8 a = live & (stack_t[sp] <= T);
            if (!any(a)) continue;
            if (!(cur & BVH_LEAF_BIT)) {
                __global const float8* n = rows + 7u * cur;
                float8 lox = n[0], hix = n[1], loy = n[2], hiy = n[3], loz = n[4], hiz = n[5];
                uint8 ref = as_uint8(n[6]);
                float kt[8];
                uint kr[8];
                int m = 0;
                for (int c = 0; c < 8; ++c) {
                    float clx = lox[c], chx = hix[c];
                    if (!(clx <= chx)) continue;   /* an empty slot: inverted box */
                    float8 tnx = ((negx ? (float8)(chx) : (float8)(clx)) - Ox) * Ix;
                    float8 tfx = ((negx ? (float8)(clx) : (float8)(chx)) - Ox) * Ix;
                    float8 tny = ((negy ? (float8)(hiy[c]) : (float8)(loy[c])) - Oy) * Iy;
                    float8 tfy = ((negy ? (float8)(loy[c]) : (float8)(hiy[c])) - Oy) * Iy;
                    float8 tnz = ((negz ? (float8)(hiz[c]) : (float8)(loz[c])) - Oz) * Iz;
                    float8 tfz = ((negz ? (float8)(loz[c]) : (float8)(hiz[c])) - Oz) * Iz;
                    float8 tn = pk_max(pk_max(tnx, tny), pk_max(tnz, tmin));
                    float8 tf = pk_min(pk_min(tfx, tfy), tfz) * 1.0000004f;
                    int8 h = a & (tn <= tf) & (tn <= T);
                    if (!any(h)) continue;
                    float8 tk = h ? tn : (float8)(INFINITY);
                    if (sp >= PK_STACK) break;   /* a probe: never seen; would drop boxes, and the check below tells */
                    stack[sp] = ref[c];
                    stack_t[sp] = tk;
                    float key = fmin(fmin(fmin(tk.s0, tk.s1), fmin(tk.s2, tk.s3)), fmin(fmin(tk.s4, tk.s5), fmin(tk.s6, tk.s7)));
                    kt[m] = key; kr[m] = (uint)sp; ++m; ++sp;
                }
                /* nearest (by its nearest lane) on top: sort the m new entries, farthest at the bottom */
                for (int i = 1; i < m; ++i) {
                    for (int j = i; j > 0 && kt[j - 1] < kt[j]; --j) {
                        float tt = kt[j]; kt[j] = kt[j - 1]; kt[j - 1] = tt;
                        uint b0 = kr[j - 1], b1 = kr[j];
                        uint rr = stack[b0]; stack[b0] = stack[b1]; stack[b1] = rr;
                        float8 st = stack_t[b0]; stack_t[b0] = stack_t[b1]; stack_t[b1] = st;
                    }
                }
                continue;
            }
            uint first = PK_LEAF_FIRST(cur), c_all = PK_LEAF_COUNT(cur), end = first + c_all;
            for (uint b = first; b < end; b += 4u) {
                uint c = end - b < 4u ? end - b : 4u;
                __global const float* q = words + 10u * b;
                for (uint l = 0u; l < c; ++l) {
                    float8 p0x = (float8)(q[l]), p0y = (float8)(q[c + l]), p0z = (float8)(q[2u * c + l]);
                    float8 p1x = (float8)(q[3u * c + l]), p1y = (float8)(q[4u * c + l]), p1z = (float8)(q[5u * c + l]);
                    float8 p2x = (float8)(q[6u * c + l]), p2y = (float8)(q[7u * c + l]), p2z = (float8)(q[8u * c + l]);
                    float8 Az = pk_pick(p0x, p0y, p0z, kz) - okz, Bz = pk_pick(p1x, p1y, p1z, kz) - okz;
                    float8 Cz = pk_pick(p2x, p2y, p2z, kz) - okz;
                    float8 Ax = pk_pick(p0x, p0y, p0z, kx) - okx - Sx * Az, Ay = pk_pick(p0x, p0y, p0z, ky) - oky - Sy * Az;
                    float8 Bx = pk_pick(p1x, p1y, p1z, kx) - okx - Sx * Bz, By = pk_pick(p1x, p1y, p1z, ky) - oky - Sy * Bz;
                    float8 Cx = pk_pick(p2x, p2y, p2z, kx) - okx - Sx * Cz, Cy = pk_pick(p2x, p2y, p2z, ky) - oky - Sy * Cz;
                    float8 e0 = Cx * By - Cy * Bx, e1 = Ax * Cy - Ay * Cx, e2 = Bx * Ay - By * Ax;
                    int8 outside = ((e0 < 0.0f) | (e1 < 0.0f) | (e2 < 0.0f)) & ((e0 > 0.0f) | (e1 > 0.0f) | (e2 > 0.0f));
                    float8 det = e0 + e1 + e2;
                    float8 tt = (e0 * Az + e1 * Bz + e2 * Cz) * Sz;
                    int8 ng = det < 0.0f;
                    float8 adet = ng ? -det : det, att = ng ? -tt : tt;
                    int8 ok = a & ~outside & (att > tmin * adet) & (att < T * adet);
                    if (any(ok)) {
                        T = ok ? tt / det : T;
                        hit |= ok;
                        live &= ~(ok & shadow);   /* an any-hit lane is done */
                        a &= live;
                    }
                }
            }
        }
        float th[8];
        vstore8(T, 0, th);
        int hl[8];
        vstore8(hit, 0, hl);
        for (uint l = 0u; l < 8u; ++l) {
            uint pix = 8u * g + l;
            if (k < cnt[l]) {
                float r = hl[l] ? th[l] : -1.0f;
                hit_t[pix * cap + k] = r;
                acc += r;
            }
        }
    }
    out[g] = acc;
}
#endif

/* render_pass for one sample per pixel without Li: sampler, filter, camera ray and accumulation only. */
__kernel void setup_pass(__global const Camera* cam, __global const float* filter_cdf, __global float4* acc0,
                         __global float4* acc1, uint sample, uint seed) {
    uint pix = get_global_id(0);
    if (pix >= cam->width * cam->height) return;
    uint px = pix % cam->width, py = pix / cam->width;
    Sampler smp;
    sampler_init(&smp, seed, pix, sample);
    float w;
    Ray ray;
    if (!camera_sample(cam, filter_cdf, px, py, &smp, &w, &ray)) return;   /* render.cl's step */
    vec3 wl = vscale(vmad(ray.o, next1d(&smp), ray.d), w);   /* keeps the sampling alive without tracing */
    float4 a0 = acc0[pix], a1 = acc1[pix];
    acc0[pix] = vf4(vadd(vxyz(a0), wl), a0.w + w);
    acc1[pix] = vf4(vadd(vxyz(a1), vmul(wl, wl)), a1.w + 1.0f);
}
