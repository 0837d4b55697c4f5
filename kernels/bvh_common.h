/* What the 2-, 4- and 8-wide traversals (bvh.h, bvh4.h, bvh8.h) share: the Hit record, the traversal stack's
   push, sort and pop, the primitive table and its intersection routines (OpenCL C 1.2).

   Primitive table: 10 words per primitive in leaf order, each leaf cut into blocks of up to 4 primitives
   stored structure of arrays (clrender/accel/primitives.py pack_leaf_blocks; bvh_isect_leaf reads it):
       triangle:   v0.xyz, v1.xyz, v2.xyz, id = its leaf reference (pack_scene: pos << 4 | lane << 2 | (c - 1),
                   clrender/accel/primitives.py leaf_refs; kernels/shapes/mesh.h finds its vertices from it:
                   this table is their only copy) or, in tables that the tests pack, its triangle number
       sphere j:   centre.xyz, radius, 0 x 5, id = j | 0x80000000
       SDF voxel:  its 8 corner values (corner x + 2y + 4z), the word offset of its record (the 3 x 4 map from
                   the world to the voxel's unit cube, after the blocks), id = shape | 0x80000000 | 0x40000000

   Hits count for tmin < t < tmax, both sides of triangles. Ray directions need not be normalised.
   Plain arithmetic instead of fmin/fmax/dot/cross: on PoCL 3.0 the builtins were 1.2-2.4x slower here. */
#ifndef CLRENDER_BVH_COMMON_H
#define CLRENDER_BVH_COMMON_H

/* BVH_LEAF_BIT, BVH_SPHERE_BIT, BVH_STACK_SIZE, BVH4_STACK_SIZE, BVH4_COUNT_SHIFT, BVH4_MAX_LEAF_COUNT: generated
   from clrender/device/layout.py ENUMS, which the host's builders read too. */
#include "math.h"   /* vec3 */
#define BVH_INLINE static inline __attribute__((always_inline))
/* a wide leaf reference's first primitive (bvh4.h, bvh8.h) */
#define BVH4_FIRST_MASK ((1u << BVH4_COUNT_SHIFT) - 1u)

typedef struct {
    float t;
    float u;      /* barycentric weight of v1 (triangles; 0 for spheres) */
    float v;      /* barycentric weight of v2 */
    uint prim;    /* the primitive's id word: a triangle's leaf reference, sphere id | 0x80000000, or an SDF voxel's
                     shape | 0x80000000 | 0x40000000 */
#ifdef BVH_COUNT_VISITS
    uint nodes, leaves, blocks;   /* benchmarks/profile_pass.py --visits: what one query visited (8-wide only) */
#endif
} Hit;

#ifdef BVH_COUNT_VISITS
#define BVH_VISIT(hit, field) ((hit)->field += 1u)
#else
#define BVH_VISIT(hit, field) ((void)0)
#endif

BVH_INLINE float bvh_min(float a, float b) { return a < b ? a : b; }

/* vload4 and any() of our own: PoCL 3.0 leaves its builtins as calls in large kernels, and a call in the
   traversal loop spills every vector register around it. Four scalar loads become one unaligned vector load. */
BVH_INLINE float4 bvh_load4(__global const float* p) { return (float4)(p[0], p[1], p[2], p[3]); }
BVH_INLINE bool bvh_any4(int4 m) { return (m.s0 | m.s1 | m.s2 | m.s3) != 0; }
BVH_INLINE float bvh_max(float a, float b) { return a > b ? a : b; }

/* The traversal stack (a node reference and its entry distance per entry; in private arrays of the caller's
   size). The wide traversals push every hit child of a node, sort what they pushed, then take the top. */
BVH_INLINE void bvh_push(uint* stack, float* stack_t, int* sp, uint ref, float t) {
    stack[*sp] = ref;
    stack_t[*sp] = t;
    ++*sp;
}

/* Insertion sort of the entries pushed since `base`, farthest first, so that the nearest is on top. */
BVH_INLINE void bvh_sort_pushed(uint* stack, float* stack_t, int base, int sp) {
    for (int i = base + 1; i < sp; ++i) {
        uint r = stack[i];
        float t = stack_t[i];
        int j = i - 1;
        while (j >= base && stack_t[j] < t) {
            stack[j + 1] = stack[j];
            stack_t[j + 1] = stack_t[j];
            --j;
        }
        stack[j + 1] = r;
        stack_t[j + 1] = t;
    }
}

/* Pop into *node, skipping entries that a later hit has moved behind t; false when the stack is empty. */
BVH_INLINE bool bvh_pop(const uint* stack, const float* stack_t, int* sp, float t, uint* node) {
    while (*sp > 0) {
        --*sp;
        if (stack_t[*sp] <= t) {
            *node = stack[*sp];
            return true;
        }
    }
    return false;
}

/* 1/x, with zero components mapped to a huge value of the same sign so slab tests never produce 0*inf. */
BVH_INLINE float bvh_safe_rcp(float x) {
    return (x > 1e-30f || x < -1e-30f) ? 1.0f / x : (as_uint(x) >> 31 ? -1e30f : 1e30f);
}

/* The ray as the primitive tests see it: origin and direction (spheres), and the ray space of the watertight
   triangle test, where the ray runs along +z from the origin: kz is the dominant axis of d, (kx, ky) the other
   two, and a vertex p maps to (p[kx] - o[kx] - sx (p[kz] - o[kz]), p[ky] - o[ky] - sy (p[kz] - o[kz])) with
   depth sz (p[kz] - o[kz]). */
typedef struct {
    vec3 o, d;
    float okx, oky, okz;   /* the origin's components along kx, ky, kz */
    float sx, sy, sz;
    int kx, ky, kz;
} BvhRay;

BVH_INLINE float bvh_pick(float4 p, int k) { return k == 0 ? p.x : (k == 1 ? p.y : p.z); }

BVH_INLINE BvhRay bvh_ray(vec3 o, vec3 d) {
    BvhRay r;
    r.o = o;
    r.d = d;
    float ax = d.x < 0.0f ? -d.x : d.x, ay = d.y < 0.0f ? -d.y : d.y, az = d.z < 0.0f ? -d.z : d.z;
    r.kz = ax > ay ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    r.kx = r.kz == 2 ? 0 : r.kz + 1;
    r.ky = r.kx == 2 ? 0 : r.kx + 1;
    float4 o4 = vf4(o, 0.0f), d4 = vf4(d, 0.0f);
    r.okx = bvh_pick(o4, r.kx); r.oky = bvh_pick(o4, r.ky); r.okz = bvh_pick(o4, r.kz);
    float dz = bvh_pick(d4, r.kz);
    r.sz = 1.0f / dz;                 /* a zero direction gives inf/NaN here, and every test then misses */
    r.sx = bvh_pick(d4, r.kx) * r.sz;
    r.sy = bvh_pick(d4, r.ky) * r.sz;
    return r;
}

/* Watertight ray/triangle test (Woop, Benthin, Wald 2013); updates (t, u, v) when a hit lies in (tmin, *t).
   Watertight because (1) a vertex maps to the same ray-space point in every triangle that has it (the
   vertices are stored, not edges), and (2) an edge's function a.x b.y - a.y b.x is computed from the same two
   points on both sides of the edge, so the two results are exact negatives of each other, and its sign is
   exact whenever it is not 0 (rounding is monotonic, so fl(ab) - fl(cd) cannot have the wrong sign). A
   function that rounds to 0 counts as inside, where the paper would redo it in double (not available on
   every OpenCL 1.2 device): a ray through an edge may hit both triangles, never neither. (2) needs the
   products rounded separately, hence FP_CONTRACT OFF: an FMA would round one product and not the other.
   -cl-fast-relaxed-math allows contraction and reassociation anyway and voids the guarantee. */
BVH_INLINE bool bvh_isect_triangle(float4 p0, float4 p1, float4 p2, const BvhRay* r, float tmin,
                                   float* t, float* u, float* v) {
#pragma OPENCL FP_CONTRACT OFF
    float az = bvh_pick(p0, r->kz) - r->okz, bz = bvh_pick(p1, r->kz) - r->okz, cz = bvh_pick(p2, r->kz) - r->okz;
    float ax = bvh_pick(p0, r->kx) - r->okx - r->sx * az, ay = bvh_pick(p0, r->ky) - r->oky - r->sy * az;
    float bx = bvh_pick(p1, r->kx) - r->okx - r->sx * bz, by = bvh_pick(p1, r->ky) - r->oky - r->sy * bz;
    float cx = bvh_pick(p2, r->kx) - r->okx - r->sx * cz, cy = bvh_pick(p2, r->ky) - r->oky - r->sy * cz;
    float e0 = cx * by - cy * bx;     /* edge p1 p2: weight of p0 */
    float e1 = ax * cy - ay * cx;     /* edge p2 p0: weight of p1 */
    float e2 = bx * ay - by * ax;     /* edge p0 p1: weight of p2 */
    if ((e0 < 0.0f || e1 < 0.0f || e2 < 0.0f) && (e0 > 0.0f || e1 > 0.0f || e2 > 0.0f)) return false;
    float det = e0 + e1 + e2;
    float tt = (e0 * az + e1 * bz + e2 * cz) * r->sz;
    float adet = det < 0.0f ? -det : det, att = det < 0.0f ? -tt : tt;
    /* det = 0 (ray in the triangle's plane) or NaN fails here too */
    if (!(att > tmin * adet && att < *t * adet)) return false;
    float inv = 1.0f / det;
    *t = tt * inv; *u = e1 * inv; *v = e2 * inv;
    return true;
}

/* Ray/sphere with a general (unnormalised) d. The discriminant is formed from the distance between the
   centre and the line (Haines et al., Ray Tracing Gems ch. 7), which stays accurate for far or grazing rays,
   and the two roots come from the cancellation-free pair q/a, c/q. */
BVH_INLINE bool bvh_isect_sphere(float4 c, float r, vec3 o, vec3 d, float tmin, float* t) {
    float fx = o.x - c.x, fy = o.y - c.y, fz = o.z - c.z;
    float a = d.x * d.x + d.y * d.y + d.z * d.z;
    float b = fx * d.x + fy * d.y + fz * d.z;                 /* half of the usual b */
    float k = b / a;
    float lx = fx - k * d.x, ly = fy - k * d.y, lz = fz - k * d.z;
    float disc = a * (r * r - (lx * lx + ly * ly + lz * lz));
    if (!(disc >= 0.0f)) return false;                         /* also rejects NaN from a zero direction */
    float cc = fx * fx + fy * fy + fz * fz - r * r;
    float s = sqrt(disc);
    float q = b >= 0.0f ? -(b + s) : -(b - s);
    float t0 = cc / q, t1 = q / a;
    float tn = bvh_min(t0, t1), tf = bvh_max(t0, t1);
    if (tn > tmin && tn < *t) { *t = tn; return true; }
    if (tf > tmin && tf < *t) { *t = tf; return true; }
    return false;
}

/* A voxel of an SDF grid (clrender/shapes/sdfgrid.py): the first root along the ray of its corner values'
   trilinear interpolation, as Mitsuba 3's sdfgrid (Hansson-Söderlund et al., JCGT 11(3) 2022). q: the voxel's
   lane l of a block of c; words: the primitive table (its record). In the voxel's unit cube the value along
   o + s d is a cubic in s; the roots of its derivative cut the span inside the cube into pieces where it is
   monotonic, and the first piece whose ends differ in sign holds the root, found by bisection to float
   precision. The cube is widened by SDF_VOXEL_PAD so that no ray slips between two voxels through rounding (the
   interpolation is continuous across their shared face). */
#define SDF_VOXEL_PAD 1e-5f
BVH_INLINE float bvh_cubic(float4 k, float s) { return ((k.w * s + k.z) * s + k.y) * s + k.x; }

BVH_INLINE bool bvh_isect_voxel(__global const float* words, __global const float* q, uint c, uint l,
                                const BvhRay* r, float tmin, float* t) {
    __global const float* m = words + as_uint(q[8u * c + l]);
    vec3 o = r->o, d = r->d;
    float ox = m[0] * o.x + m[1] * o.y + m[2] * o.z + m[3];
    float oy = m[4] * o.x + m[5] * o.y + m[6] * o.z + m[7];
    float oz = m[8] * o.x + m[9] * o.y + m[10] * o.z + m[11];
    float dx = m[0] * d.x + m[1] * d.y + m[2] * d.z;
    float dy = m[4] * d.x + m[5] * d.y + m[6] * d.z;
    float dz = m[8] * d.x + m[9] * d.y + m[10] * d.z;
    /* an axis the ray does not move along: any huge factor (its sign does not matter, both planes' products
       then share the sign of their distance) */
    float ix = (dx > 1e-30f || dx < -1e-30f) ? 1.0f / dx : 1e30f;
    float iy = (dy > 1e-30f || dy < -1e-30f) ? 1.0f / dy : 1e30f;
    float iz = (dz > 1e-30f || dz < -1e-30f) ? 1.0f / dz : 1e30f;
    const float lo = -SDF_VOXEL_PAD, hi = 1.0f + SDF_VOXEL_PAD;
    float x0 = (lo - ox) * ix, x1 = (hi - ox) * ix, y0 = (lo - oy) * iy, y1 = (hi - oy) * iy;
    float z0 = (lo - oz) * iz, z1 = (hi - oz) * iz;
    float t0 = bvh_max(bvh_max(bvh_min(x0, x1), bvh_min(y0, y1)), bvh_max(bvh_min(z0, z1), tmin));
    float t1 = bvh_min(bvh_min(bvh_max(x0, x1), bvh_max(y0, y1)), bvh_min(bvh_max(z0, z1), *t));
    if (!(t0 < t1)) return false;
    float s0 = q[l], s1 = q[c + l], s2 = q[2u * c + l], s3 = q[3u * c + l];
    float s4 = q[4u * c + l], s5 = q[5u * c + l], s6 = q[6u * c + l], s7 = q[7u * c + l];
    /* the interpolation f = s0 + b x + cy y + cz z + e xy + g xz + h yz + k xyz, taken along the ray from where its
       span in the cube starts */
    float b = s1 - s0, cy = s2 - s0, cz = s4 - s0;
    float e = s3 - s1 - s2 + s0, g = s5 - s1 - s4 + s0, h = s6 - s2 - s4 + s0;
    float k = s7 - s3 - s5 - s6 + s1 + s2 + s4 - s0;
    float px = ox + t0 * dx, py = oy + t0 * dy, pz = oz + t0 * dz;
    float4 f;   /* the cubic's coefficients, constant term first */
    f.x = s0 + b * px + cy * py + cz * pz + e * px * py + g * px * pz + h * py * pz + k * px * py * pz;
    f.y = b * dx + cy * dy + cz * dz + e * (px * dy + py * dx) + g * (px * dz + pz * dx) + h * (py * dz + pz * dy)
          + k * (px * py * dz + px * pz * dy + py * pz * dx);
    f.z = e * dx * dy + g * dx * dz + h * dy * dz + k * (px * dy * dz + py * dx * dz + pz * dx * dy);
    f.w = k * dx * dy * dz;
    float len = t1 - t0;
    /* the derivative's roots inside (0, len): 3 f.w s^2 + 2 f.z s + f.y = 0 */
    float ends[4];
    int n = 0;
    ends[n++] = 0.0f;
    float qa = 3.0f * f.w, qb = 2.0f * f.z, qc = f.y;
    float ra = INFINITY, rb = INFINITY;
    if (qa != 0.0f) {
        float disc = qb * qb - 4.0f * qa * qc;
        if (disc > 0.0f) {
            float sq = sqrt(disc);
            float qq = qb >= 0.0f ? -0.5f * (qb + sq) : -0.5f * (qb - sq);
            ra = qq / qa;
            rb = qq != 0.0f ? qc / qq : INFINITY;
        }
    } else if (qb != 0.0f) {
        ra = -qc / qb;
    }
    if (ra > rb) { float tmp = ra; ra = rb; rb = tmp; }
    if (ra > 0.0f && ra < len) ends[n++] = ra;
    if (rb > 0.0f && rb < len) ends[n++] = rb;
    ends[n++] = len;
    float sa = ends[0], fa = bvh_cubic(f, sa);
    for (int i = 1; i < n; ++i) {
        float sb = ends[i], fb = bvh_cubic(f, sb);
        if (fa == 0.0f || fa * fb <= 0.0f) {
            /* a bracket [a, z] with f(a) on fa's side and f(z) on the other or 0 */
            float a = sa, z = fa == 0.0f ? sa : sb;
            for (int it = 0; it < 24 && a < z; ++it) {
                float mid = 0.5f * (a + z), fm = bvh_cubic(f, mid);
                if (fm != 0.0f && (fm < 0.0f) == (fa < 0.0f)) a = mid; else z = mid;
            }
            float th = t0 + 0.5f * (a + z);
            if (th > tmin && th < *t) { *t = th; return true; }
        }
        sa = sb;
        fa = fb;
    }
    return false;
}

/* Intersects one leaf, up to BVH_BLOCK_LANES primitives at a time, one per float4 lane (the block layout of
   clrender/accel/primitives.py pack_leaf_blocks: row r of lane l of the block at leaf-order position b, of
   c primitives, is word 10 b + r c + l); with any_hit it stops at the first hit. Each lane runs the same
   watertight test as bvh_isect_triangle, in the same order of operations, so the guarantee holds per lane;
   sphere and SDF voxel lanes (rare) are tested one by one afterwards. */
BVH_INLINE bool bvh_isect_leaf(__global const float4* prims, uint first, uint count, const BvhRay* r,
                               float tmin, Hit* hit, bool any_hit) {
#pragma OPENCL FP_CONTRACT OFF
#ifdef BVH_PROFILE_BOXES_ONLY
    return false;   /* benchmarks/profile_pass.py: what traversal costs without the primitive tests */
#endif
    __global const float* words = (__global const float*)prims;
    bool found = false;
    uint end = first + count;
    for (uint b = first; b < end; b += 4u) {
        uint c = end - b < 4u ? end - b : 4u;
        __global const float* q = words + 10u * b;
        BVH_VISIT(hit, blocks);
#ifdef BVH_LEAF_SCALAR
        /* benchmarks only (benchmarks/ab_pass.py): the same blocks, one primitive at a time */
        for (uint l = 0u; l < c; ++l) {
            uint sid = as_uint(q[9u * c + l]);
            float4 p0 = (float4)(q[l], q[c + l], q[2u * c + l], 0.0f);
            bool h;
            if ((sid & BVH_SPHERE_BIT) && (sid & BVH_SDF_BIT)) {
                h = bvh_isect_voxel(words, q, c, l, r, tmin, &hit->t);
                if (h) { hit->u = 0.0f; hit->v = 0.0f; }
            } else if (sid & BVH_SPHERE_BIT) {
                h = bvh_isect_sphere(p0, q[3u * c + l], r->o, r->d, tmin, &hit->t);
                if (h) { hit->u = 0.0f; hit->v = 0.0f; }
            } else {
                float4 p1 = (float4)(q[3u * c + l], q[4u * c + l], q[5u * c + l], 0.0f);
                float4 p2 = (float4)(q[6u * c + l], q[7u * c + l], q[8u * c + l], 0.0f);
                h = bvh_isect_triangle(p0, p1, p2, r, tmin, &hit->t, &hit->u, &hit->v);
            }
            if (h) {
                hit->prim = sid;
                found = true;
                if (any_hit) return true;
            }
        }
        continue;
#endif
        int4 live = (int4)(0, 1, 2, 3) < (int4)((int)c);
        uint4 id = as_uint4(bvh_load4(q + 9u * c));
        int4 tri = live & ((id & (uint4)(BVH_SPHERE_BIT)) == (uint4)(0u));
        uint kx = (uint)r->kx * c, ky = (uint)r->ky * c, kz = (uint)r->kz * c, c3 = 3u * c;
        float4 okx = (float4)(r->okx), oky = (float4)(r->oky), okz = (float4)(r->okz);
        float4 sx = (float4)(r->sx), sy = (float4)(r->sy);
        float4 az = bvh_load4(q + kz) - okz, bz = bvh_load4(q + c3 + kz) - okz, cz = bvh_load4(q + 2u * c3 + kz) - okz;
        float4 ax = bvh_load4(q + kx) - okx - sx * az, ay = bvh_load4(q + ky) - oky - sy * az;
        float4 bx = bvh_load4(q + c3 + kx) - okx - sx * bz, by = bvh_load4(q + c3 + ky) - oky - sy * bz;
        float4 cx = bvh_load4(q + 2u * c3 + kx) - okx - sx * cz, cy = bvh_load4(q + 2u * c3 + ky) - oky - sy * cz;
        float4 e0 = cx * by - cy * bx;     /* edge p1 p2: weight of p0 */
        float4 e1 = ax * cy - ay * cx;     /* edge p2 p0: weight of p1 */
        float4 e2 = bx * ay - by * ax;     /* edge p0 p1: weight of p2 */
        float4 zero = (float4)(0.0f);
        int4 out = ((e0 < zero) | (e1 < zero) | (e2 < zero)) & ((e0 > zero) | (e1 > zero) | (e2 > zero));
        float4 det = e0 + e1 + e2;
        float4 tt = (e0 * az + e1 * bz + e2 * cz) * (float4)(r->sz);
        int4 neg = det < zero;
        float4 adet = neg ? -det : det, att = neg ? -tt : tt;
        /* det = 0 (ray in the triangle's plane) or NaN fails here too */
        int4 ok = tri & ~out & (att > (float4)(tmin) * adet) & (att < (float4)(hit->t) * adet);
        if (bvh_any4(ok)) {
            float4 inv = (float4)(1.0f) / det;
            float4 t4 = ok ? tt * inv : (float4)(INFINITY);
            float m = bvh_min(bvh_min(t4.x, t4.y), bvh_min(t4.z, t4.w));
            int l = t4.x == m ? 0 : (t4.y == m ? 1 : (t4.z == m ? 2 : 3));
            float4 u4 = e1 * inv, v4 = e2 * inv;
            float lane_u = l == 0 ? u4.x : (l == 1 ? u4.y : (l == 2 ? u4.z : u4.w));
            float lane_v = l == 0 ? v4.x : (l == 1 ? v4.y : (l == 2 ? v4.z : v4.w));
            uint lane_id = l == 0 ? id.x : (l == 1 ? id.y : (l == 2 ? id.z : id.w));
            hit->t = m; hit->u = lane_u; hit->v = lane_v; hit->prim = lane_id;
            found = true;
            if (any_hit) return true;
        }
        int4 sph = live & ~tri;
        if (bvh_any4(sph)) {
            for (uint l = 0u; l < c; ++l) {
                uint sid = l == 0u ? id.x : (l == 1u ? id.y : (l == 2u ? id.z : id.w));
                if (!(sid & BVH_SPHERE_BIT)) continue;
                float4 centre = (float4)(q[l], q[c + l], q[2u * c + l], 0.0f);
                if ((sid & BVH_SDF_BIT) ? bvh_isect_voxel(words, q, c, l, r, tmin, &hit->t)
                                        : bvh_isect_sphere(centre, q[c3 + l], r->o, r->d, tmin, &hit->t)) {
                    hit->u = 0.0f; hit->v = 0.0f; hit->prim = sid;
                    found = true;
                    if (any_hit) return true;
                }
            }
        }
    }
    return found;
}

#endif
