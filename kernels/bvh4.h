/* 4-wide BVH traversal: closest hit and any hit against triangles and analytic spheres (OpenCL C 1.2).
   Same functions, Hit record and primitive table as bvh.h; only the node table differs.

   Node table (collapsed from the binary tree by clrender/accel/bvh4.py): 8 float4 (128 B) per node, node k is
   nodes[8k..8k+7], children's bounds structure-of-arrays so one float4 operation tests all four:
       [8k+0] lo.x of children 0..3   [8k+1] hi.x    [8k+2] lo.y   [8k+3] hi.y   [8k+4] lo.z   [8k+5] hi.z
       [8k+6] as_float(ref) of children 0..3          [8k+7] unused
   ref: interior child = node index (bit 31 clear); leaf = 0x80000000 | (count - 1) << 27 | first.
   An empty slot is an inverted box (lo = 1e30, hi = -1e30). Node 0 is the root, always interior.

   Slab tests take the near and far plane of each axis by the sign of the direction (row 2a + (d.a < 0) is
   the near plane), so an inverted box is never entered and no min/max per axis is needed. The host checks
   that BVH4_STACK_SIZE covers the tree (every hit child of a node is pushed, then the nearest is popped). */
#ifndef CLRENDER_BVH4_H
#define CLRENDER_BVH4_H

#include "bvh_common.h"

BVH_INLINE float4 bvh4_min(float4 a, float4 b) { return a < b ? a : b; }
BVH_INLINE float4 bvh4_max(float4 a, float4 b) { return a > b ? a : b; }

/* Depth-first, front to back: the hit children of a node are pushed sorted by entry distance (nearest on top)
   and the nearest is taken at once; leaves are intersected when they come off the stack, entries that a hit
   has moved behind t are skipped. Any-hit queries do not sort. */
BVH_INLINE bool bvh4_traverse(__global const float4* nodes, __global const float4* prims, vec3 o, vec3 d,
                              float tmin, float tmax, Hit* hit, bool any_hit) {
    BvhRay ray = bvh_ray(o, d);
    /* bvh_safe_rcp of the three components with one vector division */
    float4 d4 = (float4)(d.x, d.y, d.z, 1.0f);
    int4 neg = as_int4(d4) < 0;
    float4 inv4 = (d4 > 1e-30f || d4 < -1e-30f) ? 1.0f / d4 : (neg ? (float4)(-1e30f) : (float4)(1e30f));
    int nx = inv4.x < 0.0f ? 1 : 0, ny = inv4.y < 0.0f ? 3 : 2, nz = inv4.z < 0.0f ? 5 : 4;
    int fx = nx ^ 1, fy = ny ^ 1, fz = nz ^ 1;
    float4 ox = (float4)(o.x), oy = (float4)(o.y), oz = (float4)(o.z);
    float4 ix = (float4)(inv4.x), iy = (float4)(inv4.y), iz = (float4)(inv4.z);
    float4 tmin4 = (float4)(tmin);
    uint stack[BVH4_STACK_SIZE];
    float stack_t[BVH4_STACK_SIZE];
    int sp = 0;
    uint cur = 0u;
    bool found = false;
    hit->t = tmax;
    for (;;) {
        if (!(cur & BVH_LEAF_BIT)) {
            __global const float4* n = nodes + 8u * cur;
            float4 tn = bvh4_max(bvh4_max((n[nx] - ox) * ix, (n[ny] - oy) * iy), bvh4_max((n[nz] - oz) * iz, tmin4));
            float4 tf = bvh4_min(bvh4_min((n[fx] - ox) * ix, (n[fy] - oy) * iy), (n[fz] - oz) * iz) * 1.0000004f;
            int4 m = (tn <= tf) & (tn <= (float4)(hit->t));
            uint4 ref = as_uint4(n[6]);
            /* One child hit (the commonest case): go there without the stack. */
            if (m.s0 + m.s1 + m.s2 + m.s3 == -1) {
                uint4 r = m ? ref : (uint4)(0u);
                cur = r.s0 | r.s1 | r.s2 | r.s3;
                continue;
            }
            int base = sp;
            if (m.s0) bvh_push(stack, stack_t, &sp, ref.s0, tn.s0);
            if (m.s1) bvh_push(stack, stack_t, &sp, ref.s1, tn.s1);
            if (m.s2) bvh_push(stack, stack_t, &sp, ref.s2, tn.s2);
            if (m.s3) bvh_push(stack, stack_t, &sp, ref.s3, tn.s3);
            if (sp > base) {
                if (!any_hit) bvh_sort_pushed(stack, stack_t, base, sp);
                --sp;
                cur = stack[sp];
                continue;
            }
        } else {
            if (bvh_isect_leaf(prims, cur & BVH4_FIRST_MASK, ((cur >> BVH4_COUNT_SHIFT) & (BVH4_MAX_LEAF_COUNT - 1u)) + 1u, &ray, tmin,
                               hit, any_hit)) {
                found = true;
                if (any_hit) return true;
            }
        }
        /* Pop, skipping entries that a later hit has moved behind t. */
        if (!bvh_pop(stack, stack_t, &sp, hit->t, &cur)) return found;
    }
}

#define BVH_TRAVERSE bvh4_traverse
#include "bvh_queries.h"

#endif
