/* 4-wide BVH traversal: closest hit and any hit against triangles and analytic spheres (OpenCL C 1.2).
   Same functions, Hit record and primitive table as bvh.h; only the node table differs.

   Node table (collapsed from the binary tree and quantised by clrender/accel/bvh4.py): 4 float4 (64 B, one
   cache line) per node, node k is nodes[4k..4k+3]; the children's boxes are bytes on the node's own grid,
   plane = origin + q * scale per axis, rounded outward by the host so that they hold the exact boxes:
       [4k+0] origin.xyz, lo.x bytes    [4k+1] scale.xyz, hi.x bytes    [4k+2] as_float(ref) of children 0..3
       [4k+3] lo.y bytes, hi.y bytes, lo.z bytes, hi.z bytes            (byte i of a word: child i)
   ref: interior child = node index (bit 31 clear); leaf = 0x80000000 | (count - 1) << 27 | first; 0 = an
   empty slot (node 0, the root, is nobody's child). Node 0 is the root, always interior.

   Slab tests take the near and far plane of each axis by the sign of the direction, so no min/max per axis
   is needed. The host checks
   that BVH4_STACK_SIZE covers the tree (every hit child of a node is pushed, then the nearest is popped). */
#ifndef CLRENDER_BVH4_H
#define CLRENDER_BVH4_H

#include "bvh_common.h"

#define BVH4_FIRST_MASK ((1u << BVH4_COUNT_SHIFT) - 1u)

BVH_INLINE float4 bvh4_min(float4 a, float4 b) { return a < b ? a : b; }
BVH_INLINE float4 bvh4_max(float4 a, float4 b) { return a > b ? a : b; }

/* One plane of the four children: origin + q * scale for the bytes q of `word` (child i = byte i). Rounded
   as the host's check assumes (clrender/accel/bvh4.py dequantize): the product, then the sum. */
BVH_INLINE float4 bvh4_plane(float origin, float scale, uint word) {
#pragma OPENCL FP_CONTRACT OFF
    float4 q = convert_float4(as_uchar4(word));
    return (float4)(origin) + q * (float4)(scale);
}

/* Depth-first, front to back: the hit children of a node are pushed sorted by entry distance (nearest on top)
   and the nearest is taken at once; leaves are intersected when they come off the stack, entries that a hit
   has moved behind t are skipped. Any-hit queries do not sort. */
BVH_INLINE bool bvh4_traverse(__global const float4* nodes, __global const float4* prims, float3 o, float3 d,
                              float tmin, float tmax, Hit* hit, bool any_hit) {
    BvhRay ray = bvh_ray(o, d);
    /* bvh_safe_rcp of the three components with one vector division */
    float4 d4 = (float4)(d.x, d.y, d.z, 1.0f);
    int4 neg = as_int4(d4) < 0;
    float4 inv4 = (d4 > 1e-30f || d4 < -1e-30f) ? 1.0f / d4 : (neg ? (float4)(-1e30f) : (float4)(1e30f));
    bool negx = inv4.x < 0.0f, negy = inv4.y < 0.0f, negz = inv4.z < 0.0f;
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
            __global const float4* n = nodes + 4u * cur;
            float4 r0 = n[0], r1 = n[1], r3 = n[3];
            uint4 ref = as_uint4(n[2]);
            /* the near and far plane of each axis: lo or hi by the direction's sign */
            uint wnx = negx ? as_uint(r1.w) : as_uint(r0.w), wfx = negx ? as_uint(r0.w) : as_uint(r1.w);
            uint wny = negy ? as_uint(r3.y) : as_uint(r3.x), wfy = negy ? as_uint(r3.x) : as_uint(r3.y);
            uint wnz = negz ? as_uint(r3.w) : as_uint(r3.z), wfz = negz ? as_uint(r3.z) : as_uint(r3.w);
            float4 tn = bvh4_max(bvh4_max((bvh4_plane(r0.x, r1.x, wnx) - ox) * ix, (bvh4_plane(r0.y, r1.y, wny) - oy) * iy),
                                 bvh4_max((bvh4_plane(r0.z, r1.z, wnz) - oz) * iz, tmin4));
            float4 tf = bvh4_min(bvh4_min((bvh4_plane(r0.x, r1.x, wfx) - ox) * ix, (bvh4_plane(r0.y, r1.y, wfy) - oy) * iy),
                                 (bvh4_plane(r0.z, r1.z, wfz) - oz) * iz) * 1.0000004f;
            int4 m = (tn <= tf) & (tn <= (float4)(hit->t)) & (ref != (uint4)(0u));
            int base = sp;
            if (m.s0) { stack[sp] = ref.s0; stack_t[sp] = tn.s0; ++sp; }
            if (m.s1) { stack[sp] = ref.s1; stack_t[sp] = tn.s1; ++sp; }
            if (m.s2) { stack[sp] = ref.s2; stack_t[sp] = tn.s2; ++sp; }
            if (m.s3) { stack[sp] = ref.s3; stack_t[sp] = tn.s3; ++sp; }
            if (sp > base) {
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
            if (bvh_isect_leaf(prims, cur & BVH4_FIRST_MASK, ((cur >> BVH4_COUNT_SHIFT) & (BVH4_MAX_LEAF_COUNT - 1u)) + 1u, &ray, tmin,
                               hit, any_hit)) {
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

#define BVH_TRAVERSE bvh4_traverse
#include "bvh_queries.h"

#endif
