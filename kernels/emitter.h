/* Emitters: one query record, per-type sample/pdf/eval (kernels/emitters/<type>.h), a switch that dispatches on
   the row's type tag, and scene-level light selection (a uniform choice among the N emitters).

   Measures. pdf values are solid-angle densities of wi at ref, except for delta lights (point, distant),
   whose pdf is the discrete 1 (delta = 1); emitter_pdf() of a delta light is 0 (no ray can hit it).
   For mesh area lights the density is per *point*: pdf = dist^2 / (area * |cos theta_light|), with
   cos theta_light taken against the GEOMETRIC normal ng of the triangle (the true change of measure), while
   emission is one-sided by the interpolated SHADING normal n. When one direction meets the mesh several times,
   the density of directions is the sum of the per-point pdfs; the shadow ray settles which point is seen.
   Analytic spheres seen from outside are sampled in the cone of directions they subtend (density per
   direction, independent of the point); from inside, uniformly by area.

   Shadow rays: scene_occluded(sd, q.ref, q.wi, eps, q.dist * (1 - 1e-4)); dist is INFINITY for infinite and
   directional lights (p is then only a far-away point along wi, outside the scene's bounding sphere). */
#ifndef CLRENDER_EMITTER_H
#define CLRENDER_EMITTER_H
#include "math.h"
#include "warp.h"
#include "frame.h"
#include "scene.h"

typedef struct {
    float3 ref;   /* reference point (the shading point) */
    float3 p;     /* point on the emitter (for infinite/directional lights: ref + wi * far) */
    float3 n;     /* emitter shading normal at p (area lights): decides the emitting side */
    float3 wi;    /* unit direction from ref toward the light */
    float dist;   /* shadow-ray length (INFINITY for infinite and directional lights) */
    float pdf;    /* solid-angle pdf of wi for this emitter (discrete 1 for delta lights) */
    uint delta;   /* 1 if the emitter is a delta light */
    /* additions to the agreed API: */
    float3 ng;    /* geometric normal at p (area lights): used for the area -> solid angle Jacobian */
    uint emitter; /* index of the emitter that produced the sample (NONE if unknown) */
} EmitterQuery;

/* A point well outside the scene's bounding sphere, seen from ref along a unit direction. */
INLINE float emitter_far(const SceneData* sd, float3 ref) {
    float4 b = sd->info->bounds_center;
    return 2.0f * (len3(ref - b.xyz) + b.w) + 1.0f;
}

#include "emitters/area.h"
#include "emitters/point.h"
#include "emitters/distantdisk.h"
#include "emitters/distant.h"
#include "emitters/constant.h"

/* Fill a query from a surface hit seen from ref (for emitter_pdf/emitter_eval of a BSDF-sampled ray). */
INLINE void emitter_query_from_hit(EmitterQuery* q, float3 ref, const Intersection* its) {
    q->ref = ref;
    q->p = its->p;
    q->n = its->sh.n;
    q->ng = its->ng;
    float3 d = its->p - ref;
    float l = len3(d);
    q->dist = l;
    q->wi = l > 0.0f ? d * (1.0f / l) : (float3)(0.0f, 0.0f, 1.0f);
    q->pdf = 0.0f;
    q->delta = 0u;
    q->emitter = NONE;
}

/* A query for an escaping direction d (infinite emitters only need wi). */
INLINE void emitter_query_from_direction(const SceneData* sd, EmitterQuery* q, float3 ref, float3 d) {
    q->ref = ref;
    q->wi = d;
    q->p = ref + d * emitter_far(sd, ref);
    q->n = -d;
    q->ng = -d;
    q->dist = INFINITY;
    q->pdf = 0.0f;
    q->delta = 0u;
    q->emitter = NONE;
}

INLINE bool emitter_is_infinite(uint type) { return type == EMITTER_DISTANTDISK || type == EMITTER_CONSTANT; }
INLINE bool emitter_is_delta(uint type) { return type == EMITTER_POINT || type == EMITTER_DISTANT; }

/* Sample a direction toward emitter e from q->ref; returns radiance / pdf (0 if the sample carries nothing,
   e.g. it sees the back of a one-sided area light; q->pdf is still the density of the sampled wi). */
INLINE float3 emitter_sample(const SceneData* sd, uint e, EmitterQuery* q, float2 u) {
    __global const Emitter* em = &sd->emitters[e];
    q->emitter = e;
    q->delta = 0u;
    switch (em->type) {
    case EMITTER_AREA: return area_sample(sd, em, q, u);
    case EMITTER_POINT: return point_sample(sd, em, q, u);
    case EMITTER_DISTANTDISK: return distantdisk_sample(sd, em, q, u);
    case EMITTER_DISTANT: return distant_sample(sd, em, q, u);
    case EMITTER_CONSTANT: return constant_sample(sd, em, q, u);
    default: q->pdf = 0.0f; q->dist = 0.0f; return (float3)(0.0f);
    }
}

/* Solid-angle pdf with which emitter_sample(e) would produce q->wi (and, for meshes, the point q->p). */
INLINE float emitter_pdf(const SceneData* sd, uint e, const EmitterQuery* q) {
    __global const Emitter* em = &sd->emitters[e];
    switch (em->type) {
    case EMITTER_AREA: return area_pdf(sd, em, q);
    case EMITTER_DISTANTDISK: return distantdisk_pdf(sd, em, q);
    case EMITTER_CONSTANT: return constant_pdf(sd, em, q);
    default: return 0.0f; /* delta lights: no direction has a density */
    }
}

/* Radiance leaving the emitter toward ref along -q->wi. */
INLINE float3 emitter_eval(const SceneData* sd, uint e, const EmitterQuery* q) {
    __global const Emitter* em = &sd->emitters[e];
    switch (em->type) {
    case EMITTER_AREA: return area_eval(sd, em, q);
    case EMITTER_DISTANTDISK: return distantdisk_eval(sd, em, q);
    case EMITTER_CONSTANT: return constant_eval(sd, em, q);
    default: return (float3)(0.0f);
    }
}

/* ---------------------------------------------------------------------------------- scene-level selection */

/* Choose one of the N emitters uniformly with u3.x, let it sample with u3.yz. Returns radiance / (pdf / N);
   q->pdf = emitter pdf / N, q->emitter = the chosen one. No emitters: returns 0 with pdf 0. */
INLINE float3 scene_sample_emitter(const SceneData* sd, EmitterQuery* q, float3 u3) {
    uint n = sd->info->n_emitters;
    if (n == 0u) {
        q->pdf = 0.0f; q->dist = 0.0f; q->delta = 0u; q->emitter = NONE; q->wi = (float3)(0.0f, 0.0f, 1.0f);
        q->p = q->ref; q->n = q->ng = (float3)(0.0f, 0.0f, 1.0f);
        return (float3)(0.0f);
    }
    uint e = (uint)(u3.x * (float)n);
    if (e >= n) e = n - 1u;
    float3 w = emitter_sample(sd, e, q, (float2)(u3.y, u3.z));
    q->pdf *= 1.0f / (float)n;
    return w * (float)n;
}

INLINE float scene_emitter_pdf(const SceneData* sd, uint e, const EmitterQuery* q) {
    uint n = sd->info->n_emitters;
    return n ? emitter_pdf(sd, e, q) / (float)n : 0.0f;
}

/* Radiance of an escaping ray (direction d): the sum over the infinite emitters. */
INLINE float3 scene_eval_environment(const SceneData* sd, float3 d) {
    uint n = sd->info->n_emitters;
    float3 L = (float3)(0.0f);
    EmitterQuery q;
    q.wi = d;
    for (uint e = 0u; e < n; ++e) {
        __global const Emitter* em = &sd->emitters[e];
        if (em->type == EMITTER_DISTANTDISK) L += distantdisk_eval(sd, em, &q);
        else if (em->type == EMITTER_CONSTANT) L += constant_eval(sd, em, &q);
    }
    return L;
}

/* Light-selection pdf of an escaping direction: sum over infinite emitters of (1/N) pdf_e(d). */
INLINE float scene_environment_pdf(const SceneData* sd, float3 d) {
    uint n = sd->info->n_emitters;
    float pdf = 0.0f;
    EmitterQuery q;
    q.wi = d;
    for (uint e = 0u; e < n; ++e) {
        __global const Emitter* em = &sd->emitters[e];
        if (em->type == EMITTER_DISTANTDISK) pdf += distantdisk_pdf(sd, em, &q);
        else if (em->type == EMITTER_CONSTANT) pdf += constant_pdf(sd, em, &q);
    }
    return n ? pdf / (float)n : 0.0f;
}

/* Radiance leaving the hit surface toward the viewer (wo_world points at the viewer); 0 if the shape does
   not emit or wo is on the back of its shading normal. */
INLINE float3 area_emitter_Le(const SceneData* sd, const Intersection* its, float3 wo_world) {
    uint e = sd->shapes[its->shape].emitter;
    if (e == NONE) return (float3)(0.0f);
    __global const Emitter* em = &sd->emitters[e];
    if (em->type != EMITTER_AREA) return (float3)(0.0f);
    return dot3(its->sh.n, wo_world) > 0.0f ? em->radiance.xyz : (float3)(0.0f);
}

#endif
