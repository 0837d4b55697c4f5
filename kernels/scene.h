/* The scene as the kernels see it: the packed tables (see clrender/pack.py), ray queries against the BVH,
   and the surface record of a hit. */
#ifndef CLRENDER_SCENE_H
#define CLRENDER_SCENE_H
#include "math.h"
#include "frame.h"
#include "camera.h"
/* BVH_WIDTH picks the node table the host packed (SceneBuffers.bvh_width): 4 = kernels/bvh4.h (default),
   2 = kernels/bvh.h. Both define bvh_closest_hit / bvh_any_hit over the same primitive table. */
#ifndef BVH_WIDTH
#define BVH_WIDTH 4
#endif
#if BVH_WIDTH == 4
#include "bvh4.h"
#elif BVH_WIDTH == 2
#include "bvh.h"
#else
#error "BVH_WIDTH must be 2 or 4"
#endif

/* SceneData (the scene's tables), SCENE_ARGS (the kernel-argument list of a scene: every entry point that needs
   the scene takes it first, and the host sets each table by its name s_<table>) and SCENE_INIT (gathers the
   arguments into a SceneData) are generated from clrender/device/layout.py's SCENE_TABLES. */

/* Ray counting for `clrender bench`: built with -DCLRENDER_COUNT_RAYS, scene_intersect/scene_occluded count
   their queries in the (private) SceneData. The queries take a const SceneData*, so the counters are reached
   through a cast: the struct itself lives in the kernel's private memory, never const. Normal builds
   compile none of this. */
#ifdef CLRENDER_COUNT_RAYS
#define COUNT_RAY(sd, field) (((SceneData*)(sd))->field += 1u)
#define SCENE_INIT_COUNTERS(sd) sd.n_closest = 0u; sd.n_shadow = 0u
#else
#define COUNT_RAY(sd, field) ((void)0)
#define SCENE_INIT_COUNTERS(sd) ((void)0)
#endif

typedef struct {
    float3 p;        /* hit point */
    float3 ng;       /* geometric normal (triangle winding / sphere outward) */
    Frame sh;        /* shading frame, z = interpolated shading normal */
    float2 uv;       /* spheres: (0, 0) unless the shape's BSDF has a texture (the only reader of uv) */
    float t;
    uint shape;
    uint tri;        /* triangle id, or NONE for spheres */
} Intersection;

#define SPHERE_FLAG 0x80000000u

INLINE bool scene_intersect(const SceneData* sd, const Ray* r, Intersection* its) {
    Hit h;
    COUNT_RAY(sd, n_closest);
    if (!bvh_closest_hit(sd->nodes, sd->prims, r->o, r->d, r->tmin, r->tmax, &h)) return false;
    its->t = h.t;
    if (h.prim & SPHERE_FLAG) {
        uint j = h.prim & ~SPHERE_FLAG;
        float4 s = sd->spheres[j];
        float3 p = r->o + r->d * h.t;
        float3 n = normalize3(p - s.xyz);
        its->p = s.xyz + n * s.w; /* re-project: the hit point lies on the sphere to float precision */
        its->ng = n;
        its->sh = frame_from_normal(n);
        uint shape = sd->sphere_shape[j];
        /* Only textures read uv; atan2 and acos cost more than the rest of a sphere hit. */
        if (sd->bsdfs[sd->shapes[shape].bsdf].texture != TEXTURE_NONE) {
            float u = atan2(n.y, n.x) * INV_TWOPI;
            its->uv = (float2)(u < 0.0f ? u + 1.0f : u, acos(clampf(n.z, -1.0f, 1.0f)) * INV_PI);
        } else {
            its->uv = (float2)(0.0f);
        }
        its->shape = shape;
        its->tri = NONE;
        return true;
    }
    uint4 idx = sd->tri_index[h.prim];
    float b0 = 1.0f - h.u - h.v;
    float3 p0 = sd->positions[idx.x].xyz, p1 = sd->positions[idx.y].xyz, p2 = sd->positions[idx.z].xyz;
    its->p = p0 * b0 + p1 * h.u + p2 * h.v;
    float3 ng = normalize3(cross3(p1 - p0, p2 - p0));
    its->ng = ng;
    uint flags = sd->shapes[idx.w].flags;
    float3 ns = ng;
    if (flags & SHAPE_HAS_NORMALS) {
        float3 n = sd->normals[idx.x].xyz * b0 + sd->normals[idx.y].xyz * h.u + sd->normals[idx.z].xyz * h.v;
        float l2 = dot3(n, n);
        if (l2 > 0.0f) ns = n * (1.0f / sqrt(l2));
    }
    its->sh = frame_from_normal(ns);
    if (flags & SHAPE_HAS_UVS)
        its->uv = sd->uvs[idx.x] * b0 + sd->uvs[idx.y] * h.u + sd->uvs[idx.z] * h.v;
    else
        its->uv = (float2)(h.u, h.v);
    its->shape = idx.w;
    its->tri = h.prim;
    return true;
}

INLINE bool scene_occluded(const SceneData* sd, float3 o, float3 d, float tmin, float tmax) {
    COUNT_RAY(sd, n_shadow);
    return bvh_any_hit(sd->nodes, sd->prims, o, d, tmin, tmax);
}

/* A ray leaving p along d, offset so it does not re-hit its own surface. */
INLINE Ray spawn_ray(float3 p, float3 d) {
    Ray r;
    r.o = p;
    r.d = d;
    r.tmin = ray_eps(p);
    r.tmax = INFINITY;
    return r;
}

#endif
