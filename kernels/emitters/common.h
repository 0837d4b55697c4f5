/* What every emitter kernel shares: the query record and the far point used for directional lights.
   Measures, shadow rays and the dispatch are described in emitter.h. */
#ifndef CLRENDER_EMITTERS_COMMON_H
#define CLRENDER_EMITTERS_COMMON_H
#include "math.h"
#include "warp.h"
#include "frame.h"
#include "scene.h"

typedef struct {
    vec3 ref;     /* reference point (the shading point) */
    vec3 p;       /* point on the emitter (for infinite/directional lights: ref + wi * far) */
    vec3 n;       /* emitter shading normal at p (area lights): decides the emitting side */
    vec3 wi;      /* unit direction from ref toward the light */
    float dist;   /* shadow-ray length (INFINITY for infinite and directional lights) */
    float pdf;    /* solid-angle pdf of wi for this emitter (discrete 1 for delta lights) */
    uint delta;   /* 1 if the emitter is a delta light */
    /* additions to the agreed API: */
    vec3 ng;      /* geometric normal at p (area lights): used for the area -> solid angle Jacobian */
    uint emitter; /* index of the emitter that produced the sample (NONE if unknown) */
    float2 uv;    /* surface uv at p (area lights: a textured radiance reads it) */
} EmitterQuery;

/* A point well outside the scene's bounding sphere, seen from ref along a unit direction. */
INLINE float emitter_far(const SceneData* sd, vec3 ref) {
    float4 b = sd->info->bounds_center;
    return 2.0f * (len3(vsub(ref, vxyz(b))) + b.w) + 1.0f;
}

/* Fill q for a light at the point p (delta in position: pdf 1, delta 1); returns 1 / dist^2 (0 at p itself). */
INLINE float emitter_point_query(EmitterQuery* q, vec3 p) {
    vec3 d = vsub(p, q->ref);
    float d2 = dot3(d, d);
    float l = sqrt(d2);
    q->p = p;
    q->wi = l > 0.0f ? vscale(d, 1.0f / l) : v3(0.0f, 0.0f, 1.0f);
    q->n = vneg(q->wi);
    q->ng = vneg(q->wi);
    q->dist = l;
    q->pdf = 1.0f;
    q->delta = 1u;
    return d2 > 0.0f ? 1.0f / d2 : 0.0f;
}

#endif
