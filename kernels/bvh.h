/* BVH traversal: closest hit and any hit against triangles and analytic spheres (OpenCL C 1.2).

   Node table (built by clrender/accel/bvh.py): 2-wide nodes of 4 float4 (64 B); node k is nodes[4k..4k+3]:
       [4k+0] = A.lo.xyz, as_float(A.ref)      [4k+2] = B.lo.xyz, as_float(B.ref)
       [4k+1] = A.hi.xyz, as_float(A.count)    [4k+3] = B.hi.xyz, as_float(B.count)
   A and B are the two children. Interior child: ref = node index (bit 31 clear), count = 0. Leaf child:
   ref = 0x80000000 | first, count = primitives (0 only for an empty slot); its primitives are rows
   first .. first+count-1 of the primitive table. Node 0 is the root; even a one-leaf or empty scene has it.

   The primitive table, the Hit record and the primitive intersection routines are in bvh_common.h (shared
   with the 4-wide traversal of bvh4.h, which the renderer uses by default; scene.h picks one by BVH_WIDTH).

   Hits count for tmin < t < tmax, both sides of triangles. Ray directions need not be normalised.
   Plain arithmetic instead of fmin/fmax/dot/cross: on PoCL 3.0 the builtins were 1.2-2.4x slower here. */
#ifndef CLRENDER_BVH_H
#define CLRENDER_BVH_H

#include "bvh_common.h"

/* Slab test of one child box: is [entry, exit] non-empty within (tmin, tmax)? The exit distance is widened
   by a few ulps so rounding cannot drop a primitive lying on a box face. */
BVH_INLINE bool bvh_slab(float4 lo, float4 hi, vec3 o, vec3 inv, float tmin, float tmax, float* entry) {
    float x0 = (lo.x - o.x) * inv.x, x1 = (hi.x - o.x) * inv.x;
    float y0 = (lo.y - o.y) * inv.y, y1 = (hi.y - o.y) * inv.y;
    float z0 = (lo.z - o.z) * inv.z, z1 = (hi.z - o.z) * inv.z;
    float tn = bvh_max(bvh_max(bvh_min(x0, x1), bvh_min(y0, y1)), bvh_max(bvh_min(z0, z1), tmin));
    float tf = bvh_min(bvh_min(bvh_max(x0, x1), bvh_max(y0, y1)), bvh_max(z0, z1)) * 1.0000004f;
    *entry = tn;
    return tn <= tf && tn <= tmax;
}

/* Shared traversal: depth-first, nearer child first, leaves intersected as soon as their box is hit so the
   shortened t culls the interior children of the same node. */
BVH_INLINE bool bvh_traverse(__global const float4* nodes, __global const float4* prims, vec3 o, vec3 d,
                             float tmin, float tmax, Hit* hit, bool any_hit) {
    BvhRay ray = bvh_ray(o, d);
    vec3 inv = v3(bvh_safe_rcp(d.x), bvh_safe_rcp(d.y), bvh_safe_rcp(d.z));
    uint stack[BVH_STACK_SIZE];
    float stack_t[BVH_STACK_SIZE];
    int sp = 0;
    uint node = 0;
    bool found = false;
    hit->t = tmax;
    for (;;) {
        __global const float4* n = nodes + 4 * node;
        float4 alo = n[0], ahi = n[1], blo = n[2], bhi = n[3];
        float ta, tb;
        bool ha = bvh_slab(alo, ahi, o, inv, tmin, hit->t, &ta);
        bool hb = bvh_slab(blo, bhi, o, inv, tmin, hit->t, &tb);
        uint aref = as_uint(alo.w), bref = as_uint(blo.w);
        if (ha && (aref & BVH_LEAF_BIT)) {
            if (bvh_isect_leaf(prims, aref & ~BVH_LEAF_BIT, as_uint(ahi.w), &ray, tmin, hit, any_hit)) {
                found = true;
                if (any_hit) return true;
            }
            ha = false;
        }
        if (hb && (bref & BVH_LEAF_BIT)) {
            if (bvh_isect_leaf(prims, bref & ~BVH_LEAF_BIT, as_uint(bhi.w), &ray, tmin, hit, any_hit)) {
                found = true;
                if (any_hit) return true;
            }
            hb = false;
        }
        /* A leaf just hit may have moved t in front of the interior children. */
        ha = ha && ta <= hit->t;
        hb = hb && tb <= hit->t;
        if (ha && hb) {
            uint near = ta <= tb ? aref : bref, far = ta <= tb ? bref : aref;
            float tfar = ta <= tb ? tb : ta;
            if (sp < BVH_STACK_SIZE) bvh_push(stack, stack_t, &sp, far, tfar);
            node = near;
            continue;
        }
        if (ha) { node = aref; continue; }
        if (hb) { node = bref; continue; }
        if (!bvh_pop(stack, stack_t, &sp, hit->t, &node)) return found;
    }
}

#define BVH_TRAVERSE bvh_traverse
#include "bvh_queries.h"

#endif
