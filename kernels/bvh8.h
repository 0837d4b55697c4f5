/* 8-wide BVH traversal: closest hit and any hit against triangles and analytic spheres (OpenCL C 1.2).
   Same functions, Hit record and primitive table as bvh.h and bvh4.h; only the node table differs.

   Node table (collapsed from the binary tree by clrender/accel/bvh4.py with width 8): 7 float8 (224 B) per
   node, node k is rows 7k..7k+6 of float8, children's bounds structure-of-arrays so one float8 operation
   (an AVX register on a CPU) tests all eight:
       [7k+0] lo.x of children 0..7   [7k+1] hi.x    [7k+2] lo.y   [7k+3] hi.y   [7k+4] lo.z   [7k+5] hi.z
       [7k+6] as_float(ref) of children 0..7
   ref and empty slots as in bvh4.h. The traversal is bvh4.h's with eight lanes. */
#ifndef CLRENDER_BVH8_H
#define CLRENDER_BVH8_H

#include "bvh_common.h"

/* The hit children as a bit mask, and its lowest set bit. On PoCL for x86 (CLRENDER_INLINE_BUILTINS, AVX), one
   vmovmskps and tzcnt; the portable forms elsewhere, and with -DBVH_PORTABLE_BITS (tests/test_bvh.py traces with both).
   Against the sum of the lanes and a branchless push of all eight children: x1.06 on the Cornell twin. */
#if defined(CLRENDER_INLINE_BUILTINS) && !defined(CLRENDER_BUILTIN_CALLS) && !defined(BVH_PORTABLE_BITS) && \
    defined(__AVX__)
BVH_INLINE uint bvh8_bits(int8 m) { return (uint)__builtin_ia32_movmskps256(as_float8(m)); }
BVH_INLINE uint bvh_ctz(uint x) { return (uint)__builtin_ctz(x); }
#else
BVH_INLINE uint bvh8_bits(int8 m) {
    int8 b = m & (int8)(1, 2, 4, 8, 16, 32, 64, 128);
    int4 h = b.lo | b.hi;
    return (uint)(h.s0 | h.s1 | h.s2 | h.s3);
}
BVH_INLINE uint bvh_ctz(uint x) { return 31u - clz(x & (0u - x)); }
#endif

/* A float8 whose lanes can be read by a run-time index. */
typedef union { float8 v; float a[8]; } BvhLanes8;

BVH_INLINE float8 bvh8_min(float8 a, float8 b) { return a < b ? a : b; }
BVH_INLINE float8 bvh8_max(float8 a, float8 b) { return a > b ? a : b; }

BVH_INLINE bool bvh8_traverse(__global const float4* nodes, __global const float4* prims, vec3 o, vec3 d,
                              float tmin, float tmax, Hit* hit, bool any_hit) {
    BvhRay ray = bvh_ray(o, d);
    float4 d4 = (float4)(d.x, d.y, d.z, 1.0f);
    int4 neg = as_int4(d4) < 0;
    float4 inv4 = (d4 > 1e-30f || d4 < -1e-30f) ? 1.0f / d4 : (neg ? (float4)(-1e30f) : (float4)(1e30f));
    int nx = inv4.x < 0.0f ? 1 : 0, ny = inv4.y < 0.0f ? 3 : 2, nz = inv4.z < 0.0f ? 5 : 4;
    int fx = nx ^ 1, fy = ny ^ 1, fz = nz ^ 1;
    float8 ox = (float8)(o.x), oy = (float8)(o.y), oz = (float8)(o.z);
    float8 ix = (float8)(inv4.x), iy = (float8)(inv4.y), iz = (float8)(inv4.z);
    float8 tmin8 = (float8)(tmin);
    __global const float8* rows = (__global const float8*)nodes;
    uint stack[BVH8_STACK_SIZE];
    float stack_t[BVH8_STACK_SIZE];
    int sp = 0;
    uint cur = 0u;
    bool found = false;
    hit->t = tmax;
#ifdef BVH_COUNT_VISITS
    hit->nodes = 0u; hit->leaves = 0u; hit->blocks = 0u;
#endif
    for (;;) {
        if (!(cur & BVH_LEAF_BIT)) {
            __global const float8* n = rows + 7u * cur;
            BVH_VISIT(hit, nodes);
            float8 tn = bvh8_max(bvh8_max((n[nx] - ox) * ix, (n[ny] - oy) * iy), bvh8_max((n[nz] - oz) * iz, tmin8));
            float8 tf = bvh8_min(bvh8_min((n[fx] - ox) * ix, (n[fy] - oy) * iy), (n[fz] - oz) * iz) * 1.0000004f;
            int8 m = (tn <= tf) & (tn <= (float8)(hit->t));
            uint bits = bvh8_bits(m);
            if (bits != 0u) {
                __global const uint* refs = (__global const uint*)(n + 6);
                uint i0 = bvh_ctz(bits);
                bits &= bits - 1u;
                if (bits == 0u) {           /* one child hit (the commonest case): go there */
                    cur = refs[i0];
                    continue;
                }
                BvhLanes8 tl;
                tl.v = tn;
                uint i1 = bvh_ctz(bits);
                bits &= bits - 1u;
                if (bits == 0u) {           /* two: the nearer next, the farther onto the stack */
                    bool first = any_hit || tl.a[i0] <= tl.a[i1];
                    uint near = first ? i0 : i1, far = first ? i1 : i0;
                    bvh_push(stack, stack_t, &sp, refs[far], tl.a[far]);
                    cur = refs[near];
                    continue;
                }
                /* three or more: push them all, sort the new entries farthest first, go to the nearest */
                int base = sp;
                bvh_push(stack, stack_t, &sp, refs[i0], tl.a[i0]);
                bvh_push(stack, stack_t, &sp, refs[i1], tl.a[i1]);
                do {
                    uint i = bvh_ctz(bits);
                    bits &= bits - 1u;
                    bvh_push(stack, stack_t, &sp, refs[i], tl.a[i]);
                } while (bits != 0u);
                if (!any_hit) bvh_sort_pushed(stack, stack_t, base, sp);
                --sp;
                cur = stack[sp];
                continue;
            }
        } else {
            uint count = ((cur >> BVH4_COUNT_SHIFT) & (BVH4_MAX_LEAF_COUNT - 1u)) + 1u;
            BVH_VISIT(hit, leaves);
            if (bvh_isect_leaf(prims, cur & BVH4_FIRST_MASK, count, &ray, tmin, hit, any_hit)) {
                found = true;
                if (any_hit) return true;
            }
        }
        /* Pop, skipping entries that a later hit has moved behind t. */
        if (!bvh_pop(stack, stack_t, &sp, hit->t, &cur)) return found;
    }
}

#define BVH_TRAVERSE bvh8_traverse
#include "bvh_queries.h"

#endif
