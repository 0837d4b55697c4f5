/* Benchmark only (benchmarks/simd_probe.py): what shading 8 paths at once in float8 lanes would give, before any
   redesign. path_mis over diffuse triangle meshes under mesh area lights (constant albedo and radiance, box
   filter, no environment: the diffuse Cornell twin), one work-item per 8 pixels, each lane one pixel's path.
   Traversal, gathers from the scene tables, light selection and the random numbers stay per lane (scalar, the
   same functions as the render kernel, drawn in the same order, so the paths are the render kernel's own);
   the surface, emission, light-sample, MIS, roulette and BSDF-sample arithmetic runs in float8 lanes. */
#include "li.h"
#include "filter.h"

#define W 8
typedef union { float8 v; float a[W]; } F8;
typedef union { int8 v; int a[W]; } I8;
typedef struct { float8 x, y, z; } V8;

static inline V8 v8(float8 x, float8 y, float8 z) { V8 r; r.x = x; r.y = y; r.z = z; return r; }
static inline V8 v8_add(V8 a, V8 b) { return v8(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline V8 v8_sub(V8 a, V8 b) { return v8(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline V8 v8_mul(V8 a, V8 b) { return v8(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline V8 v8_scale(V8 a, float8 s) { return v8(a.x * s, a.y * s, a.z * s); }
static inline float8 v8_dot(V8 a, V8 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline V8 v8_cross(V8 a, V8 b) { return v8(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }
static inline float8 f8_abs(float8 x) { return as_float8(as_int8(x) & (int8)(0x7fffffff)); }
static inline float8 f8_max(float8 a, float8 b) { return a > b ? a : b; }
static inline float8 f8_min(float8 a, float8 b) { return a < b ? a : b; }
static inline float8 f8_sel(float8 a, float8 b, int8 m) { return m ? b : a; }   /* b where m */
static inline V8 v8_sel(V8 a, V8 b, int8 m) { return v8(f8_sel(a.x, b.x, m), f8_sel(a.y, b.y, m), f8_sel(a.z, b.z, m)); }
static inline float8 f8_sqrt(float8 x) {
#if defined(CLRENDER_INLINE_BUILTINS) && defined(__AVX__)
    return __builtin_ia32_sqrtps256(x);
#else
    return sqrt(x);
#endif
}
static inline float8 f8_rint(float8 x) { return (x + 12582912.0f) - 12582912.0f; }   /* |x| < 2^22 */
static inline int f8_any(int8 m) {
    int4 h = m.lo | m.hi;
    return (h.s0 | h.s1 | h.s2 | h.s3) != 0;
}

/* sin_cos (math.h) in lanes */
static inline void f8_sin_cos(float8 x, float8* s, float8* c) {
    float8 qf = f8_rint(x * 0.63661977236758134f);
    float8 r = ((x - qf * 1.5703125f) - qf * 4.837512969970703125e-4f) - qf * 7.549790126404332e-8f;
    float8 r2 = r * r;
    float8 sr = r + r * r2 * (-1.6666666666666667e-1f + r2 * (8.3333333333333333e-3f + r2 * (-1.9841269841269841e-4f
                    + r2 * 2.7557319223985891e-6f)));
    float8 cr = 1.0f + r2 * (-0.5f + r2 * (4.1666666666666667e-2f + r2 * (-1.3888888888888889e-3f
                    + r2 * (2.4801587301587302e-5f - r2 * 2.7557319223985891e-7f))));
    int8 q = convert_int8(qf) & 3;
    int8 odd = (q & 1) != 0;
    float8 sv = odd ? cr : sr, cv = odd ? sr : cr;
    *s = ((q & 2) != 0) ? -sv : sv;
    *c = (((q + 1) & 2) != 0) ? -cv : cv;
}

/* square_to_cosine_hemisphere (warp.h: concentric disk) in lanes */
static inline V8 f8_cosine_hemisphere(float8 ux, float8 uy) {
    float8 a = 2.0f * ux - 1.0f, b = 2.0f * uy - 1.0f;
    int8 zero = (a == 0.0f) & (b == 0.0f);
    int8 first = a * a > b * b;
    float8 r = first ? a : b;
    float8 sa = first ? a : (float8)(1.0f), sb = first ? (float8)(1.0f) : b;   /* avoid 0/0 in the unused branch */
    float8 phi = first ? (M_PI_F_ / 4.0f) * (b / sa) : (M_PI_F_ / 2.0f) - (M_PI_F_ / 4.0f) * (a / sb);
    float8 s, c;
    f8_sin_cos(phi, &s, &c);
    float8 dx = zero ? (float8)(0.0f) : r * c, dy = zero ? (float8)(0.0f) : r * s;
    float8 z = f8_sqrt(f8_max(1.0f - dx * dx - dy * dy, 0.0f));
    return v8(dx, dy, z);
}

/* frame_from_normal (frame.h) in lanes */
static inline void f8_frame(V8 n, V8* s, V8* t) {
    float8 sign = n.z >= 0.0f ? (float8)(1.0f) : (float8)(-1.0f);
    float8 a = -1.0f / (sign + n.z);
    float8 b = n.x * n.y * a;
    *s = v8(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    *t = v8(b, sign + n.y * n.y * a, -n.y);
}

/* eight loads into one vector (dead lanes pass a valid index) */
static inline float8 g8(__global const float* p, uint8 i) {
    return (float8)(p[i.s0], p[i.s1], p[i.s2], p[i.s3], p[i.s4], p[i.s5], p[i.s6], p[i.s7]);
}
static inline uint8 g8u(__global const uint* p, uint8 i) {
    return (uint8)(p[i.s0], p[i.s1], p[i.s2], p[i.s3], p[i.s4], p[i.s5], p[i.s6], p[i.s7]);
}
/* the normals table's 16-bit fixed point (mesh_snorm16) in lanes */
static inline float8 h8(__global const ushort* p, uint8 i) {
    int8 h = convert_int8((uint8)(p[i.s0], p[i.s1], p[i.s2], p[i.s3], p[i.s4], p[i.s5], p[i.s6], p[i.s7]));
    return convert_float8(h - ((h & 0x8000) << 1)) * (1.0f / 32767.0f);
}

#define LANE_SET3(V, l, f3) do { (V##x).a[l] = (f3).x; (V##y).a[l] = (f3).y; (V##z).a[l] = (f3).z; } while (0)

__kernel void simd_pass(SCENE_ARGS, __global const Camera* cam, __global const float* filter_cdf,
                        __global float4* acc0, uint pixel_count, uint sample_offset, uint spp, uint seed) {
    uint g = get_global_id(0);
    if (W * g >= pixel_count) return;
    SCENE_INIT(sd);
    Sampler smp[W];
    uint pix[W];
    I8 valid;
    for (int l = 0; l < W; ++l) {
        pix[l] = W * g + (uint)l;
        valid.a[l] = pix[l] < pixel_count ? -1 : 0;
    }
    V8 sum = v8((float8)(0.0f), (float8)(0.0f), (float8)(0.0f));
    float8 wsum = (float8)(0.0f);
    uint rr_depth = sd.info->rr_depth, max_depth = sd.info->max_depth;
    /* Path regeneration: a lane whose path ended starts its pixel's next sample at once, so the lanes stay full
       until the last samples (all lanes stepping one vertex per trip of the loop). */
    uint next_s[W];
#ifdef PROBE_UNROLL
#pragma unroll
#endif
    for (int l = 0; l < W; ++l) next_s[l] = valid.a[l] ? 0u : spp;
    V8 ro, rd, L, beta, prev_p;
    ro = rd = L = prev_p = v8((float8)(0.0f), (float8)(0.0f), (float8)(0.0f));
    beta = v8((float8)(1.0f), (float8)(1.0f), (float8)(1.0f));
    float8 prev_pdf = (float8)(0.0f);
    int8 after_delta = (int8)(-1), alive = (int8)(0), pending = (int8)(0);
    uint8 depth = (uint8)(0u);
    F8 fw;
    for (;;) {
        {
            I8 al, pe;
            al.v = alive;
            pe.v = pending;
            int8 fresh_m = (int8)(0);
            I8 fresh; fresh.v = fresh_m;
            F8 ox, oy, oz, dx, dy, dz, Lx, Ly, Lz;
            ox.v = ro.x; oy.v = ro.y; oz.v = ro.z; dx.v = rd.x; dy.v = rd.y; dz.v = rd.z;
            Lx.v = L.x; Ly.v = L.y; Lz.v = L.z;
            F8 sx, sy, sz, sw;
            sx.v = (float8)(0.0f); sy.v = (float8)(0.0f); sz.v = (float8)(0.0f); sw.v = (float8)(0.0f);
#ifdef PROBE_UNROLL
#pragma unroll
#endif
            for (int l = 0; l < W; ++l) {
                if (al.a[l]) continue;
                if (pe.a[l]) {   /* a finished path: into the pixel's sums (non-finite samples dropped) */
                    vec3 v = v3(Lx.a[l], Ly.a[l], Lz.a[l]);
                    if (all_finite(v) && isfinite(fw.a[l])) {
                        sx.a[l] = v.x * fw.a[l]; sy.a[l] = v.y * fw.a[l]; sz.a[l] = v.z * fw.a[l]; sw.a[l] = fw.a[l];
                    }
                }
                if (next_s[l] >= spp) continue;
                uint p = pix[l];
                sampler_init(&smp[l], seed, p, sample_offset + next_s[l]);
                next_s[l] += 1u;
                float w;
                float2 off = filter_sample_guided(cam, filter_cdf, next2d(&smp[l]), &w);
                Ray ray = camera_ray_lens(cam, (float)(p % cam->width) + 0.5f + off.x,
                                          (float)(p / cam->width) + 0.5f + off.y, (float2)(0.5f, 0.5f));
                ox.a[l] = ray.o.x; oy.a[l] = ray.o.y; oz.a[l] = ray.o.z;
                dx.a[l] = ray.d.x; dy.a[l] = ray.d.y; dz.a[l] = ray.d.z;
                fw.a[l] = w;
                fresh.a[l] = -1;
            }
            sum = v8_add(sum, v8(sx.v, sy.v, sz.v));
            wsum += sw.v;
            ro = v8(ox.v, oy.v, oz.v);
            rd = v8(dx.v, dy.v, dz.v);
            int8 f = fresh.v;
            V8 zero3 = v8((float8)(0.0f), (float8)(0.0f), (float8)(0.0f));
            L = v8_sel(L, zero3, f);
            beta = v8_sel(beta, v8((float8)(1.0f), (float8)(1.0f), (float8)(1.0f)), f);
            prev_p = v8_sel(prev_p, ro, f);
            prev_pdf = f ? (float8)(0.0f) : prev_pdf;
            after_delta |= f;
            depth = f ? (uint8)(0u) : depth;
            pending = alive | f;
            alive |= f;
        }
        if (!f8_any(alive)) break;
        {
            /* trace (per lane) */
            I8 al; al.v = alive;
            I8 hprim; F8 bu, bv;
            I8 hit;
#ifdef PROBE_UNROLL
#pragma unroll
#endif
            for (int l = 0; l < W; ++l) {
                hit.a[l] = 0; hprim.a[l] = 0; bu.a[l] = 0.0f; bv.a[l] = 0.0f;
                if (!al.a[l]) continue;
                Hit h;
                vec3 o = v3(ro.x[l], ro.y[l], ro.z[l]), d = v3(rd.x[l], rd.y[l], rd.z[l]);
                if (!bvh_closest_hit(sd.nodes, sd.prims, o, d, 0.0f, INFINITY, &h)) continue;
                hit.a[l] = -1; hprim.a[l] = (int)h.prim; bu.a[l] = h.u; bv.a[l] = h.v;
            }
#ifdef PROBE_GATHER8
            /* gathers in lanes: index vectors, eight loads each (dead lanes read row 0) */
            int8 live = hit.v;
            uint8 ref = as_uint8(live ? hprim.v : (int8)(0));
            uint8 pos = ref >> PRIM_REF_POS_SHIFT, lane = (ref >> 2) & 3u, cc = (ref & 3u) + 1u;
            uint8 qb = 10u * (pos - lane) + lane;
            __global const float* words = (__global const float*)sd.prims;
            F8 p0x, p0y, p0z, p1x, p1y, p1z, p2x, p2y, p2z;
            p0x.v = g8(words, qb); p0y.v = g8(words, qb + cc); p0z.v = g8(words, qb + 2u * cc);
            p1x.v = g8(words, qb + 3u * cc); p1y.v = g8(words, qb + 4u * cc); p1z.v = g8(words, qb + 5u * cc);
            p2x.v = g8(words, qb + 6u * cc); p2y.v = g8(words, qb + 7u * cc); p2z.v = g8(words, qb + 8u * cc);
            /* the shape: the mesh whose vertex range holds the first vertex index (a fixed-depth search) */
            uint8 i0 = g8u(sd.tri_index, 3u * pos), i1 = g8u(sd.tri_index, 3u * pos + 1u), i2 = g8u(sd.tri_index, 3u * pos + 2u);
            uint8 lo = (uint8)(0u), hi = (uint8)(sd.info->n_meshes - 1u);
            __global const uint* mv = (__global const uint*)sd.mesh_vertices;
            for (uint it = 0u; it < 32u; ++it) {
                int8 more = as_int8(lo < hi);
                if (!f8_any(more)) break;
                uint8 mid = (lo + hi + 1u) >> 1;
                int8 le = as_int8(g8u(mv, 2u * mid) <= i0);
                lo = (more & le) ? mid : lo;
                hi = (more & ~le) ? mid - 1u : hi;
            }
            uint8 shape = g8u(mv, 2u * lo + 1u);
            __global const uint* shw = (__global const uint*)sd.shapes;
            uint sw_ = (uint)(sizeof(Shape) / 4u);
            uint8 sflags = g8u(shw, sw_ * shape + 1u), sbsdf = g8u(shw, sw_ * shape + 2u), semit = g8u(shw, sw_ * shape + 3u);
            float8 sarea = as_float8(g8u(shw, sw_ * shape + 7u));
            int8 hasn_m = live & as_int8((sflags & (uint)SHAPE_HAS_NORMALS) != 0u);
            F8 hasn; hasn.v = hasn_m ? (float8)(1.0f) : (float8)(0.0f);
            __global const ushort* nrm = sd.normals;
            uint8 j0 = hasn_m ? i0 : (uint8)(0u), j1 = hasn_m ? i1 : (uint8)(0u), j2 = hasn_m ? i2 : (uint8)(0u);
            F8 n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z;
            n0x.v = h8(nrm, 3u * j0); n0y.v = h8(nrm, 3u * j0 + 1u); n0z.v = h8(nrm, 3u * j0 + 2u);
            n1x.v = h8(nrm, 3u * j1); n1y.v = h8(nrm, 3u * j1 + 1u); n1z.v = h8(nrm, 3u * j1 + 2u);
            n2x.v = h8(nrm, 3u * j2); n2y.v = h8(nrm, 3u * j2 + 1u); n2z.v = h8(nrm, 3u * j2 + 2u);
            __global const float* bw = (__global const float*)sd.bsdfs;
            uint bsz = (uint)(sizeof(Bsdf) / 4u), boff = (uint)(__builtin_offsetof(Bsdf, p) / 4u);
            F8 alb_r, alb_g, alb_b;
            alb_r.v = g8(bw, bsz * sbsdf + boff); alb_g.v = g8(bw, bsz * sbsdf + boff + 1u);
            alb_b.v = g8(bw, bsz * sbsdf + boff + 2u);
            I8 emits; emits.v = live & as_int8(semit != (uint8)(NONE));
            uint8 ei = emits.v ? semit : (uint8)(0u);
            __global const float* ew = (__global const float*)sd.emitters;
            uint esz = (uint)(sizeof(Emitter) / 4u), eoff = (uint)(__builtin_offsetof(Emitter, p) / 4u);
            F8 le_r, le_g, le_b, inv_area, eprob;
            le_r.v = g8(ew, esz * ei + eoff); le_g.v = g8(ew, esz * ei + eoff + 1u); le_b.v = g8(ew, esz * ei + eoff + 2u);
            inv_area.v = emits.v ? 1.0f / sarea : (float8)(0.0f);
            eprob.v = emits.v ? (float8)(1.0f / (float)sd.info->n_emitters) : (float8)(0.0f);   /* uniform selection */
#else
            F8 p0x, p0y, p0z, p1x, p1y, p1z, p2x, p2y, p2z;
            F8 n0x, n0y, n0z, n1x, n1y, n1z, n2x, n2y, n2z, hasn, alb_r, alb_g, alb_b, le_r, le_g, le_b, inv_area, eprob;
            I8 emits;
            al.v = hit.v;
#ifdef PROBE_UNROLL
#pragma unroll
#endif
            for (int l = 0; l < W; ++l) {
                emits.a[l] = 0; hasn.a[l] = 0.0f;
                p0x.a[l] = p0y.a[l] = p0z.a[l] = p1x.a[l] = p1y.a[l] = p1z.a[l] = p2x.a[l] = p2y.a[l] = p2z.a[l] = 0.0f;
                p1x.a[l] = 1.0f; p2y.a[l] = 1.0f;
                n0x.a[l] = n0y.a[l] = n0z.a[l] = n1x.a[l] = n1y.a[l] = n1z.a[l] = n2x.a[l] = n2y.a[l] = n2z.a[l] = 0.0f;
                alb_r.a[l] = alb_g.a[l] = alb_b.a[l] = 0.0f;
                le_r.a[l] = le_g.a[l] = le_b.a[l] = 0.0f;
                inv_area.a[l] = 0.0f; eprob.a[l] = 0.0f;
                if (!al.a[l]) continue;
                uint prim = (uint)hprim.a[l];
                uint shape = scene_triangle_shape(&sd, prim >> PRIM_REF_POS_SHIFT);
                __global const Shape* sh = &sd.shapes[shape];
                MeshTriangle t = mesh_triangle(&sd, prim);
                p0x.a[l] = t.p0.x; p0y.a[l] = t.p0.y; p0z.a[l] = t.p0.z;
                p1x.a[l] = t.p1.x; p1y.a[l] = t.p1.y; p1z.a[l] = t.p1.z;
                p2x.a[l] = t.p2.x; p2y.a[l] = t.p2.y; p2z.a[l] = t.p2.z;
                if (sh->flags & SHAPE_HAS_NORMALS) {
                    vec3 a = mesh_normal(&sd, t.i0), b = mesh_normal(&sd, t.i1), c = mesh_normal(&sd, t.i2);
                    n0x.a[l] = a.x; n0y.a[l] = a.y; n0z.a[l] = a.z;
                    n1x.a[l] = b.x; n1y.a[l] = b.y; n1z.a[l] = b.z;
                    n2x.a[l] = c.x; n2y.a[l] = c.y; n2z.a[l] = c.z;
                    hasn.a[l] = 1.0f;
                }
                float4 alb = sd.bsdfs[sh->bsdf].p.diffuse.albedo;
                alb_r.a[l] = alb.x; alb_g.a[l] = alb.y; alb_b.a[l] = alb.z;
                if (sh->emitter != NONE) {
                    float4 rad = sd.emitters[sh->emitter].p.area.radiance;
                    le_r.a[l] = rad.x; le_g.a[l] = rad.y; le_b.a[l] = rad.z;
                    emits.a[l] = -1;
                    inv_area.a[l] = 1.0f / sh->area;
                    eprob.a[l] = scene_emitter_prob(&sd, sh->emitter);
                }
            }
#endif
            alive &= hit.v;
            /* the surface (lanes) */
            V8 p0 = v8(p0x.v, p0y.v, p0z.v), p1 = v8(p1x.v, p1y.v, p1z.v), p2 = v8(p2x.v, p2y.v, p2z.v);
            float8 b0 = 1.0f - bu.v - bv.v;
            V8 p = v8_add(v8_add(v8_scale(p0, b0), v8_scale(p1, bu.v)), v8_scale(p2, bv.v));
            V8 e1 = v8_sub(p1, p0), e2 = v8_sub(p2, p0);
            V8 c = v8_cross(e1, e2);
            float8 a2 = f8_sqrt(v8_dot(c, c));
            V8 ng = v8_scale(c, 1.0f / a2);
            float8 m0 = f8_max(f8_max(f8_abs(p0.x), f8_abs(p0.y)), f8_abs(p0.z));
            float8 m1 = f8_max(f8_max(f8_abs(p1.x), f8_abs(p1.y)), f8_abs(p1.z));
            float8 m2 = f8_max(f8_max(f8_abs(p2.x), f8_abs(p2.y)), f8_abs(p2.z));
            float8 off = SPAWN_OFFSET * f8_max(m0, f8_max(m1, m2));
            float8 k = off / a2;
            V8 e12 = v8_sub(p2, p1);
            float8 w0 = f8_max(b0, k * f8_sqrt(v8_dot(e12, e12)));
            float8 w1 = f8_max(bu.v, k * f8_sqrt(v8_dot(e2, e2)));
            float8 w2 = f8_max(bv.v, k * f8_sqrt(v8_dot(e1, e1)));
            float8 ws = w0 + w1 + w2;
            V8 po = v8_scale(v8_add(v8_add(v8_scale(p0, w0), v8_scale(p1, w1)), v8_scale(p2, w2)), 1.0f / ws);
            po = v8_sel(p, po, (ws > 0.0f) & (ws < INFINITY));
            V8 ni = v8_add(v8_add(v8_scale(v8(n0x.v, n0y.v, n0z.v), b0), v8_scale(v8(n1x.v, n1y.v, n1z.v), bu.v)),
                           v8_scale(v8(n2x.v, n2y.v, n2z.v), bv.v));
            float8 nl2 = v8_dot(ni, ni);
            int8 use_ni = (hasn.v > 0.0f) & (nl2 > 0.0f);
            V8 n = v8_sel(ng, v8_scale(ni, 1.0f / f8_sqrt(f8_sel((float8)(1.0f), nl2, use_ni))), use_ni);
            V8 fs, ft;
            f8_frame(n, &fs, &ft);
            /* emission reached, MIS against emitter sampling at the previous vertex */
            {
                V8 dd = v8_sub(p, prev_p);
                float8 d2 = v8_dot(dd, dd), dl = f8_sqrt(d2);
                V8 wi = v8_scale(dd, 1.0f / dl);
                float8 cosl = f8_abs(v8_dot(ng, wi));
                float8 lpdf = ((cosl > 0.0f) & (d2 > 0.0f)) ? inv_area.v * d2 / cosl * eprob.v : (float8)(0.0f);
                float8 mw = prev_pdf + lpdf > 0.0f ? prev_pdf / (prev_pdf + lpdf) : (float8)(0.0f);
                mw = after_delta ? (float8)(1.0f) : mw;
                int8 front = v8_dot(n, rd) < 0.0f;
                int8 add = alive & emits.v & front;
                float8 ww = add ? mw : (float8)(0.0f);
                L = v8_add(L, v8_mul(beta, v8_scale(v8(le_r.v, le_g.v, le_b.v), ww)));
            }
            alive &= as_int8(depth + 1u < (uint8)(max_depth));
            /* emitter sampling: pick (per lane), then lanes */
            F8 lp0x, lp0y, lp0z, lp1x, lp1y, lp1z, lp2x, lp2y, lp2z, lux, luy, lr, lg, lb, lia, lprob;
            al.v = alive;
    #ifdef PROBE_UNROLL
#pragma unroll
#endif
        for (int l = 0; l < W; ++l) {
                lp0x.a[l] = lp0y.a[l] = lp0z.a[l] = lp1x.a[l] = lp1y.a[l] = lp1z.a[l] = 0.0f;
                lp2x.a[l] = lp2y.a[l] = lp2z.a[l] = 0.0f;
                lp1x.a[l] = 1.0f; lp2y.a[l] = 1.0f;
                lux.a[l] = luy.a[l] = 0.0f; lr.a[l] = lg.a[l] = lb.a[l] = 0.0f; lia.a[l] = 0.0f; lprob.a[l] = 0.0f;
                if (!al.a[l]) continue;
                float a = next1d(&smp[l]);
                float2 u = next2d(&smp[l]);
                float prob;
                uint e = scene_pick_emitter(&sd, a, &prob);
                __global const Emitter* em = &sd.emitters[e];
                __global const Shape* sh = &sd.shapes[em->shape];
                __global const float* cdf = sd.cdf + sh->cdf;
                uint i = shape_cdf_search(cdf, sh->count, u.x);
                float lo = i > 0u ? cdf[i - 1u] : 0.0f, hi = cdf[i];
                float ux = hi > lo ? (u.x - lo) / (hi - lo) : 0.5f;
                ux = clampf(ux, 0.0f, 0x1.fffffep-1f);
                MeshTriangle t = mesh_triangle(&sd, sd.tri_refs[sh->first + i]);
                lp0x.a[l] = t.p0.x; lp0y.a[l] = t.p0.y; lp0z.a[l] = t.p0.z;
                lp1x.a[l] = t.p1.x; lp1y.a[l] = t.p1.y; lp1z.a[l] = t.p1.z;
                lp2x.a[l] = t.p2.x; lp2y.a[l] = t.p2.y; lp2z.a[l] = t.p2.z;
                lux.a[l] = ux; luy.a[l] = u.y;
                float4 rad = em->p.area.radiance;
                lr.a[l] = rad.x; lg.a[l] = rad.y; lb.a[l] = rad.z;
                lia.a[l] = 1.0f / sh->area;
                lprob.a[l] = prob;
            }
            V8 wo_w;
            float8 ldist;
            F8 unocc;
            {
                float8 su = f8_sqrt(lux.v);
                float8 bx = 1.0f - su, by = luy.v * su, bz = 1.0f - bx - by;
                V8 q0 = v8(lp0x.v, lp0y.v, lp0z.v), q1 = v8(lp1x.v, lp1y.v, lp1z.v), q2 = v8(lp2x.v, lp2y.v, lp2z.v);
                V8 lpnt = v8_add(v8_add(v8_scale(q0, bz), v8_scale(q1, bx)), v8_scale(q2, by));
                V8 lc = v8_cross(v8_sub(q1, q0), v8_sub(q2, q0));
                V8 lng = v8_scale(lc, 1.0f / f8_sqrt(v8_dot(lc, lc)));
                V8 dd = v8_sub(lpnt, p);
                float8 d2 = v8_dot(dd, dd), dl = f8_sqrt(d2);
                V8 wi = v8_scale(dd, 1.0f / dl);
                float8 cosl = v8_dot(lng, wi);
                float8 pdf = ((f8_abs(cosl) > 0.0f) & (d2 > 0.0f)) ? lia.v * d2 / f8_abs(cosl) * lprob.v : (float8)(0.0f);
                int8 ok = alive & (pdf > 0.0f) & (cosl < 0.0f);
                /* diffuse f, both sides above */
                float8 cwi = -v8_dot(rd, n), cwo = v8_dot(wi, n);
                ok &= (cwi > 0.0f) & (cwo > 0.0f);
                float8 bpdf = cwo * INV_PI;
                float8 mw = pdf / (pdf + bpdf);
                float8 scale = ok ? cwo * INV_PI * mw / pdf : (float8)(0.0f);
                /* the shadow rays (per lane) */
                I8 okl; okl.v = ok;
        #ifdef PROBE_UNROLL
#pragma unroll
#endif
        for (int l = 0; l < W; ++l) {
                    unocc.a[l] = 0.0f;
                    if (!okl.a[l]) continue;
                    vec3 wl = v3(wi.x[l], wi.y[l], wi.z[l]);
                    vec3 ngl = v3(ng.x[l], ng.y[l], ng.z[l]);
                    vec3 pol = v3(po.x[l], po.y[l], po.z[l]);
                    vec3 o = dot3(wl, ngl) < 0.0f ? vsub(pol, vscale(ngl, off[l])) : vadd(pol, vscale(ngl, off[l]));
                    vec3 q = v3(lpnt.x[l], lpnt.y[l], lpnt.z[l]);
                    vec3 sd3 = vsub(q, o);
                    float len = len3(sd3);
                    float tmax = len * (1.0f - 1e-4f) - ray_eps(q);
                    if (!(tmax > 0.0f) || !bvh_any_hit(sd.nodes, sd.prims, o, vscale(sd3, 1.0f / len), 0.0f, tmax))
                        unocc.a[l] = 1.0f;
                }
                scale *= unocc.v;
                V8 alb = v8(alb_r.v, alb_g.v, alb_b.v);
                L = v8_add(L, v8_mul(v8_mul(beta, alb), v8_scale(v8(lr.v, lg.v, lb.v), scale)));
            }
            /* roulette (Nori's) and the BSDF sample */
            F8 rr, u0, u1;
            al.v = alive;
            I8 do_rr; do_rr.v = as_int8(depth >= (uint8)(rr_depth));
            float8 q = f8_min(f8_max(f8_max(beta.x, beta.y), beta.z), 0.99f);
            F8 qq; qq.v = q;
    #ifdef PROBE_UNROLL
#pragma unroll
#endif
        for (int l = 0; l < W; ++l) {
                rr.a[l] = 1.0f; u0.a[l] = u1.a[l] = 0.5f;
                if (!al.a[l]) continue;
                if (do_rr.a[l]) {
                    if (!(next1d(&smp[l]) < qq.a[l])) { rr.a[l] = 0.0f; continue; }
                }
                float2 u = next2d(&smp[l]);
                u0.a[l] = u.x; u1.a[l] = u.y;
            }
            alive &= rr.v > 0.0f;
            beta = v8_scale(beta, 1.0f / f8_sel((float8)(1.0f), q, alive & do_rr.v));
            V8 wo = f8_cosine_hemisphere(u0.v, u1.v);
            float8 cwi = -v8_dot(rd, n);
            alive &= (cwi > 0.0f) & (wo.z > 0.0f);
            beta = v8_mul(beta, v8(alb_r.v, alb_g.v, alb_b.v));
            prev_pdf = wo.z * INV_PI;
            after_delta = (int8)(0);
            prev_p = p;
            V8 dn = v8_add(v8_add(v8_scale(fs, wo.x), v8_scale(ft, wo.y)), v8_scale(n, wo.z));
            int8 below = v8_dot(dn, ng) < 0.0f;
            float8 so = below ? -off : off;
            ro = v8_add(po, v8_scale(ng, so));
            rd = dn;
            depth += (uint8)(1u);
        }
    }
#ifdef PROBE_UNROLL
#pragma unroll
#endif
    for (int l = 0; l < W; ++l) {
        if (!valid.a[l]) continue;
        float4 a = acc0[pix[l]];
        acc0[pix[l]] = (float4)(a.x + sum.x[l], a.y + sum.y[l], a.z + sum.z[l], a.w + wsum[l]);
    }
}
