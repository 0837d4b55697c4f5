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

#define BVH4_FIRST_MASK ((1u << BVH4_COUNT_SHIFT) - 1u)

BVH_INLINE float8 bvh8_min(float8 a, float8 b) { return a < b ? a : b; }
BVH_INLINE float8 bvh8_max(float8 a, float8 b) { return a > b ? a : b; }

BVH_INLINE bool bvh8_traverse(__global const float4* nodes, __global const float4* prims, float3 o, float3 d,
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
    uint stack[BVH8_STACK_SIZE + 1];   /* + 1: a branchless push stores a missed child one past the top */
    float stack_t[BVH8_STACK_SIZE + 1];
    int sp = 0;
    uint cur = 0u;
    bool found = false;
    hit->t = tmax;
    for (;;) {
        if (!(cur & BVH_LEAF_BIT)) {
            __global const float8* n = rows + 7u * cur;
            float8 tn = bvh8_max(bvh8_max((n[nx] - ox) * ix, (n[ny] - oy) * iy), bvh8_max((n[nz] - oz) * iz, tmin8));
            float8 tf = bvh8_min(bvh8_min((n[fx] - ox) * ix, (n[fy] - oy) * iy), (n[fz] - oz) * iz) * 1.0000004f;
            int8 m = (tn <= tf) & (tn <= (float8)(hit->t));
            int k = m.s0 + m.s1 + m.s2 + m.s3 + m.s4 + m.s5 + m.s6 + m.s7;   /* minus the number of hits */
            int base = sp;
            if (k == -1) {
                /* One child hit (the commonest case): go there without the stack. */
                uint8 r = m ? as_uint8(n[6]) : (uint8)(0u);
                uint4 r4 = r.lo | r.hi;
                cur = r4.s0 | r4.s1 | r4.s2 | r4.s3;
                continue;
            }
            if (k != 0) {
                uint8 ref = as_uint8(n[6]);
                /* every child is stored, sp passes the hit ones (no branch per child) */
                stack[sp] = ref.s0; stack_t[sp] = tn.s0; sp -= m.s0;
                stack[sp] = ref.s1; stack_t[sp] = tn.s1; sp -= m.s1;
                stack[sp] = ref.s2; stack_t[sp] = tn.s2; sp -= m.s2;
                stack[sp] = ref.s3; stack_t[sp] = tn.s3; sp -= m.s3;
                stack[sp] = ref.s4; stack_t[sp] = tn.s4; sp -= m.s4;
                stack[sp] = ref.s5; stack_t[sp] = tn.s5; sp -= m.s5;
                stack[sp] = ref.s6; stack_t[sp] = tn.s6; sp -= m.s6;
                stack[sp] = ref.s7; stack_t[sp] = tn.s7; sp -= m.s7;
                if (!any_hit) {
                    /* Insertion sort of the new entries, farthest at the bottom. */
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
                --sp;
                cur = stack[sp];
                continue;
            }
        } else {
            uint count = ((cur >> BVH4_COUNT_SHIFT) & (BVH4_MAX_LEAF_COUNT - 1u)) + 1u;
            if (bvh_isect_leaf(prims, cur & BVH4_FIRST_MASK, count, &ray, tmin, hit, any_hit)) {
                found = true;
                if (any_hit) return true;
            }
        }
        /* Pop, skipping entries that a later hit has moved behind t. */
        for (;;) {
            if (sp == 0) return found;
            --sp;
            if (stack_t[sp] <= hit->t) break;
        }
        cur = stack[sp];
    }
}

#define BVH_TRAVERSE bvh8_traverse
#include "bvh_queries.h"

#endif
