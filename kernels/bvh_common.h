/* What the 2-wide (bvh.h) and 4-wide (bvh4.h) traversals share: the Hit record, the primitive table and its
   intersection routines (OpenCL C 1.2).

   Primitive table, 3 float4 per primitive in leaf order (clrender/accel/primitives.py):
       triangle i: [v0.xyz, as_float(i)], [e1.xyz, 0], [e2.xyz, 0]      (e1 = v1 - v0, e2 = v2 - v0)
       sphere j:   [centre.xyz, as_float(j | 0x80000000)], [radius, 0, 0, 0], [0, 0, 0, 0]

   Hits count for tmin < t < tmax, both sides of triangles. Ray directions need not be normalised.
   Plain arithmetic instead of fmin/fmax/dot/cross: on PoCL 3.0 the builtins were 1.2-2.4x slower here. */
#ifndef CLRENDER_BVH_COMMON_H
#define CLRENDER_BVH_COMMON_H

#define BVH_LEAF_BIT 0x80000000u
#define BVH_SPHERE_BIT 0x80000000u
#define BVH_INLINE static inline __attribute__((always_inline))

typedef struct {
    float t;
    float u;      /* barycentric weight of v1 (triangles; 0 for spheres) */
    float v;      /* barycentric weight of v2 */
    uint prim;    /* the primitive's id word: triangle id, or sphere id | 0x80000000 */
} Hit;

BVH_INLINE float bvh_min(float a, float b) { return a < b ? a : b; }
BVH_INLINE float bvh_max(float a, float b) { return a > b ? a : b; }

/* 1/x, with zero components mapped to a huge value of the same sign so slab tests never produce 0*inf. */
BVH_INLINE float bvh_safe_rcp(float x) {
    return (x > 1e-30f || x < -1e-30f) ? 1.0f / x : (as_uint(x) >> 31 ? -1e30f : 1e30f);
}

/* Möller–Trumbore with precomputed edges; updates (t, u, v) when a hit lies in (tmin, *t). */
BVH_INLINE bool bvh_isect_triangle(float4 p0, float4 e1, float4 e2, float3 o, float3 d, float tmin,
                                   float* t, float* u, float* v) {
    float px = d.y * e2.z - d.z * e2.y, py = d.z * e2.x - d.x * e2.z, pz = d.x * e2.y - d.y * e2.x;
    float det = e1.x * px + e1.y * py + e1.z * pz;
    if (det == 0.0f) return false;
    float inv = 1.0f / det;
    float sx = o.x - p0.x, sy = o.y - p0.y, sz = o.z - p0.z;
    float bu = (sx * px + sy * py + sz * pz) * inv;
    if (bu < 0.0f || bu > 1.0f) return false;
    float qx = sy * e1.z - sz * e1.y, qy = sz * e1.x - sx * e1.z, qz = sx * e1.y - sy * e1.x;
    float bv = (d.x * qx + d.y * qy + d.z * qz) * inv;
    if (bv < 0.0f || bu + bv > 1.0f) return false;
    float tt = (e2.x * qx + e2.y * qy + e2.z * qz) * inv;
    if (!(tt > tmin && tt < *t)) return false;
    *t = tt; *u = bu; *v = bv;
    return true;
}

/* Ray/sphere with a general (unnormalised) d. The discriminant is formed from the distance between the
   centre and the line (Haines et al., Ray Tracing Gems ch. 7), which stays accurate for far or grazing rays,
   and the two roots come from the cancellation-free pair q/a, c/q. */
BVH_INLINE bool bvh_isect_sphere(float4 c, float r, float3 o, float3 d, float tmin, float* t) {
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

/* Intersects one leaf; with any_hit it stops at the first hit. */
BVH_INLINE bool bvh_isect_leaf(__global const float4* prims, uint first, uint count, float3 o, float3 d,
                               float tmin, Hit* hit, bool any_hit) {
    bool found = false;
    for (uint i = first; i < first + count; ++i) {
        __global const float4* p = prims + 3 * i;
        float4 r0 = p[0];
        uint id = as_uint(r0.w);
        bool h;
        if (id & BVH_SPHERE_BIT) {
            h = bvh_isect_sphere(r0, p[1].x, o, d, tmin, &hit->t);
            if (h) { hit->u = 0.0f; hit->v = 0.0f; }
        } else {
            h = bvh_isect_triangle(r0, p[1], p[2], o, d, tmin, &hit->t, &hit->u, &hit->v);
        }
        if (h) {
            hit->prim = id;
            found = true;
            if (any_hit) return true;
        }
    }
    return found;
}

#endif
