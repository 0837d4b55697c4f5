/* The two ray queries every BVH layout offers, over its BVH_TRAVERSE(nodes, prims, o, d, tmin, tmax, hit,
   any_hit) routine; included at the end of kernels/bvh.h and kernels/bvh4.h (one of them per program). */
#ifndef CLRENDER_BVH_QUERIES_H
#define CLRENDER_BVH_QUERIES_H

/* Closest hit in (tmin, tmax); *hit is written only when there is one. */
bool bvh_closest_hit(__global const float4* nodes, __global const float4* prims, vec3 o, vec3 d,
                     float tmin, float tmax, Hit* hit) {
    Hit h;
    bool found = BVH_TRAVERSE(nodes, prims, o, d, tmin, tmax, &h, false);
    if (found) *hit = h;
    return found;
}

/* Anything in (tmin, tmax)? Stops at the first hit (shadow rays). */
bool bvh_any_hit(__global const float4* nodes, __global const float4* prims, vec3 o, vec3 d,
                 float tmin, float tmax) {
    Hit h;
    return BVH_TRAVERSE(nodes, prims, o, d, tmin, tmax, &h, true);
}

/* Profiling builds only (benchmarks/profile_pass.py): BVH_RECORD(kind, o, d, tmin, tmax) sees every query
   before it runs (kind 0 = closest hit, 1 = any hit). A macro of the functions' own names, so the callers
   in scene.h stay as they are; it does not expand inside itself, so the inner calls are the functions. */
#ifdef BVH_RECORD
#define bvh_closest_hit(nodes, prims, o, d, tmin, tmax, hit) \
    (BVH_RECORD(0u, (o), (d), (tmin), (tmax)), bvh_closest_hit((nodes), (prims), (o), (d), (tmin), (tmax), (hit)))
#define bvh_any_hit(nodes, prims, o, d, tmin, tmax) \
    (BVH_RECORD(1u, (o), (d), (tmin), (tmax)), bvh_any_hit((nodes), (prims), (o), (d), (tmin), (tmax)))
#endif

#endif
