/* The scene as the kernels see it: the packed tables (see clrender/pack.py), ray queries against the BVH,
   and the surface record of a hit. */
#ifndef CLRENDER_SCENE_H
#define CLRENDER_SCENE_H
#include "math.h"
#include "frame.h"
#include "camera.h"
#include "derivatives.h"
/* BVH_WIDTH picks the node table the host packed (SceneBuffers.bvh_width): 8 = kernels/bvh8.h (default: ×1.15
   on the Cornell twin and ×1.12 on a 1 M-triangle mesh over 4-wide, benchmarks/README.md), 4 = kernels/bvh4.h,
   2 = kernels/bvh.h. All define bvh_closest_hit / bvh_any_hit over the same primitive
   table. */
#ifndef BVH_WIDTH
#define BVH_WIDTH 8
#endif
#if BVH_WIDTH == 4
#include "bvh4.h"
#elif BVH_WIDTH == 8
#include "bvh8.h"
#elif BVH_WIDTH == 2
#include "bvh.h"
#else
#error "BVH_WIDTH must be 2, 4 or 8"
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
    vec3 p;          /* hit point */
    vec3 ng;         /* geometric normal (triangle winding / sphere outward) */
    Frame sh;        /* shading frame, z = interpolated shading normal */
    float2 uv;       /* spheres: (0, 0) unless the shape's BSDF has a texture (the only reader of uv) */
    float t;
    vec3 po;         /* where rays leaving the surface start from, before the offset along ng (spawn_origin) */
    float off;       /* how far they are pushed off the surface along ng */
    uint shape;
    uint tri;        /* the triangle's leaf reference (Hit.prim, see kernels/shapes/mesh.h), or NONE for spheres */
#ifdef CLR_SURFACE_DERIVATIVES
    vec3 dpdu, dpdv;   /* Mitsuba's dp/du, dp/dv in world space where SHAPE_NEEDS_UV (else 0): derivatives.h */
#endif
} Intersection;

/* Spawned rays start off the surface, on the side they leave to, and take tmin = 0, so they neither re-hit
   their own surface nor step past a neighbouring one (an offset along the ray, as tmin was, skips every
   surface within it: at a concave edge, the wall next to p). The origin is p pushed along ng by a bound on
   the rounding errors of p and of the triangle test near t = 0, which are a few ulps of the largest
   coordinate involved (p comes from barycentrics or a re-projection; the watertight test translates the
   vertices to the ray's origin): SPAWN_OFFSET is 64 such ulps (4 was the least that passed
   tests/test_watertight.py, 2 failed it). The same idea as Wächter and Binder (Ray Tracing Gems ch. 6) and
   pbrt-v4, scaled by the triangle's vertices rather than by p, since p can be small on a large triangle.
   Near an edge, p is first moved into its triangle by the same distance (Intersection.po): pushing along ng
   alone leaves a point on a 90-degree concave edge on the neighbouring wall's plane. */
#define SPAWN_OFFSET 3.814697265625e-06f   /* 64 * 2^-24 */


/* The shapes' surface/sample/pdf functions (kernels/shapes/<name>.h) behind generated switches on Shape.type. */
#include "gen/mesh_dispatch.h"

/* The shape of the triangle at leaf-order position pos: the mesh whose vertex range holds its first vertex index
   (mesh_vertices rows: (first vertex, shape), ascending; a binary search over a table of one row per mesh). */
INLINE uint scene_triangle_shape(const SceneData* sd, uint pos) {
    uint i0 = sd->tri_index[3u * pos];
#if defined(CLR_SEARCH_STEPS) && defined(CLR_WAVEFRONT_STAGES)
    /* the last row whose first vertex is <= i0, in the fixed steps of math.h's table_count_le */
    uint n = 0u, count = sd->info->n_meshes;
#pragma unroll
    for (int s = CLR_SEARCH_STEPS - 1; s >= 0; --s) {
        uint next = n + (1u << s);
        if (next <= count && sd->mesh_vertices[next - 1u].x <= i0) n = next;
    }
    return sd->mesh_vertices[n - 1u].y;
#else
    uint lo = 0u, hi = sd->info->n_meshes - 1u;
    while (lo < hi) {
        uint mid = (lo + hi + 1u) >> 1;
        if (sd->mesh_vertices[mid].x <= i0) lo = mid; else hi = mid - 1u;
    }
    return sd->mesh_vertices[lo].y;
#endif
}

/* A closest-hit query is two steps, so that a wavefront driver can run them as kernels of their own: the trace
   (the BVH alone: t, barycentrics, primitive) and the surface reconstruction (the shape's point, normals, frame and
   uv at that hit). scene_intersect does both. */
INLINE bool scene_trace(const SceneData* sd, const Ray* r, Hit* h) {
    COUNT_RAY(sd, n_closest);
    return bvh_closest_hit(sd->nodes, sd->prims, r->o, r->d, r->tmin, r->tmax, h);
}

INLINE bool scene_surface(const SceneData* sd, const Ray* r, const Hit* h, Intersection* its) {
    its->t = h->t;
    uint shape = (h->prim & BVH_SPHERE_BIT)
                     ? ((h->prim & BVH_SDF_BIT) ? (h->prim & ~(BVH_SPHERE_BIT | BVH_SDF_BIT))
                                                : sd->sphere_shape[h->prim & ~BVH_SPHERE_BIT])
                     : scene_triangle_shape(sd, h->prim >> PRIM_REF_POS_SHIFT);
    its->shape = shape;
    return shape_surface(sd, &sd->shapes[shape], r, h, its);
}

INLINE bool scene_intersect(const SceneData* sd, const Ray* r, Intersection* its) {
    Hit h;
    return scene_trace(sd, r, &h) && scene_surface(sd, r, &h, its);
}

INLINE bool scene_occluded(const SceneData* sd, vec3 o, vec3 d, float tmin, float tmax) {
    COUNT_RAY(sd, n_shadow);
    return bvh_any_hit(sd->nodes, sd->prims, o, d, tmin, tmax);
}

/* The origin of a ray leaving the surface hit at `its` along d (see SPAWN_OFFSET). */
INLINE vec3 spawn_origin(const Intersection* its, vec3 d) {
    vec3 o = vscale(its->ng, its->off);
    return dot3(d, its->ng) < 0.0f ? vsub(its->po, o) : vadd(its->po, o);
}

/* A ray leaving the surface hit at `its` along d. */
INLINE Ray spawn_ray_from(const Intersection* its, vec3 d) {
    Ray r;
    r.o = spawn_origin(its, d);
    r.d = d;
    r.tmin = 0.0f;
    r.tmax = INFINITY;
    return r;
}

/* A ray from a point p on no known surface, offset along the ray by ray_eps(p) instead (unlike spawn_ray_from,
   this skips anything within ray_eps(p) of p). */
INLINE Ray spawn_ray(vec3 p, vec3 d) {
    Ray r;
    r.o = p;
    r.d = d;
    r.tmin = ray_eps(p);
    r.tmax = INFINITY;
    return r;
}

#endif
