/* Emitters: the query record (emitters/common.h), per-plugin sample/pdf/eval (kernels/emitters/<prefix>.h) reached
   through switches generated from the registered plugins (gen/emitter_dispatch.h: emitter_row_sample/pdf/eval,
   see clrender/device/codegen.py), and scene-level light selection (a uniform choice among the N emitters, or
   one proportional to their power: scene_pick_emitter).
   Kernels test the row's flags (EMITTER_DELTA, EMITTER_INFINITE, EMITTER_SURFACE), never its type; infinite
   emitters are also listed in the `infinite` index table.

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

#include "gen/emitter_dispatch.h"
#include "shapes/common.h"   /* shape_cdf_search */

/* Fill a query from a surface hit seen from ref (for emitter_pdf/emitter_eval of a BSDF-sampled ray). */
INLINE void emitter_query_from_hit(EmitterQuery* q, vec3 ref, const Intersection* its) {
    q->ref = ref;
    q->p = its->p;
    q->n = its->sh.n;
    q->ng = its->ng;
    vec3 d = vsub(its->p, ref);
    float l = len3(d);
    q->dist = l;
    q->wi = l > 0.0f ? vscale(d, 1.0f / l) : v3(0.0f, 0.0f, 1.0f);
    q->pdf = 0.0f;
    q->delta = 0u;
    q->emitter = NONE;
    q->uv = its->uv;
}

/* A query for an escaping direction d (infinite emitters only need wi). */
INLINE void emitter_query_from_direction(const SceneData* sd, EmitterQuery* q, vec3 ref, vec3 d) {
    q->ref = ref;
    q->wi = d;
    q->p = vmad(d, emitter_far(sd, ref), ref);
    q->n = vneg(d);
    q->ng = vneg(d);
    q->dist = INFINITY;
    q->pdf = 0.0f;
    q->delta = 0u;
    q->emitter = NONE;
}

/* Sample a direction toward emitter e from q->ref; returns radiance / pdf (0 if the sample carries nothing,
   e.g. it sees the back of a one-sided area light; q->pdf is still the density of the sampled wi). */
INLINE vec3 emitter_sample(const SceneData* sd, uint e, EmitterQuery* q, float2 u) {
    __global const Emitter* em = &sd->emitters[e];
    q->emitter = e;
    q->delta = (em->flags & EMITTER_DELTA) ? 1u : 0u;
    return emitter_row_sample(sd, em, q, u);
}

/* Solid-angle pdf with which emitter_sample(e) would produce q->wi (and, for meshes, the point q->p); 0 for delta
   lights, whose headers define no pdf: no direction has a density. */
INLINE float emitter_pdf(const SceneData* sd, uint e, const EmitterQuery* q) {
    return emitter_row_pdf(sd, &sd->emitters[e], q);
}

/* Radiance leaving the emitter toward ref along -q->wi. */
INLINE vec3 emitter_eval(const SceneData* sd, uint e, const EmitterQuery* q) {
    return emitter_row_eval(sd, &sd->emitters[e], q);
}

/* ---------------------------------------------------------------------------------- scene-level selection */

/* Which emitter u picks, and with what probability: uniformly among the N (Nori files, and Mitsuba files by
   default), or by the selection CDF that pack_scene built from the emitters' powers (info->emitter_cdf != NONE;
   clrender/pack.py). Every pdf that MIS compares goes through scene_emitter_prob, so both strategies agree. */
INLINE uint scene_pick_emitter(const SceneData* sd, float u, float* prob) {
    uint n = sd->info->n_emitters;
    uint off = sd->info->emitter_cdf;
    if (off == NONE) {
        uint e = (uint)(u * (float)n);
        if (e >= n) e = n - 1u;
        *prob = 1.0f / (float)n;
        return e;
    }
    __global const float* cdf = sd->cdf + off;
    uint e = shape_cdf_search(cdf, n, u);
    *prob = cdf[e] - (e > 0u ? cdf[e - 1u] : 0.0f);
    return e;
}

INLINE float scene_emitter_prob(const SceneData* sd, uint e) {
    uint n = sd->info->n_emitters;
    if (n == 0u) return 0.0f;
    uint off = sd->info->emitter_cdf;
    if (off == NONE) return 1.0f / (float)n;
    __global const float* cdf = sd->cdf + off;
    return cdf[e] - (e > 0u ? cdf[e - 1u] : 0.0f);
}

/* Choose one of the N emitters with u3.x (scene_pick_emitter), let it sample with u3.yz. Returns
   radiance / (pdf * P(e)); q->pdf = emitter pdf * P(e), q->emitter = the chosen one. No emitters: returns 0 with
   pdf 0. */
INLINE vec3 scene_sample_emitter(const SceneData* sd, EmitterQuery* q, vec3 u3) {
    uint n = sd->info->n_emitters;
    float prob = 0.0f;
    uint e = n ? scene_pick_emitter(sd, u3.x, &prob) : 0u;
    if (n == 0u || !(prob > 0.0f)) {
        q->pdf = 0.0f; q->dist = 0.0f; q->delta = 0u; q->emitter = NONE; q->wi = v3(0.0f, 0.0f, 1.0f);
        q->p = q->ref; q->n = q->ng = v3(0.0f, 0.0f, 1.0f);
        return v3s(0.0f);
    }
    vec3 w = emitter_sample(sd, e, q, (float2)(u3.y, u3.z));
    q->pdf *= prob;
    return vscale(w, 1.0f / prob);
}

INLINE float scene_emitter_pdf(const SceneData* sd, uint e, const EmitterQuery* q) {
    float prob = scene_emitter_prob(sd, e);
    return prob > 0.0f ? emitter_pdf(sd, e, q) * prob : 0.0f;
}

/* The number of infinite emitters: the scene's, fixed when the host builds the program for it (CLR_N_INFINITE),
   so that the loops below have a constant trip count (0 or 1 in most scenes: unrolled, no per-item loop left). */
#ifdef CLR_N_INFINITE
#define N_INFINITE(sd) ((uint)CLR_N_INFINITE)
#else
#define N_INFINITE(sd) ((sd)->info->n_infinite)
#endif

/* Radiance of an escaping ray (direction d): the sum over the infinite emitters (an index list, so an escaped
   ray visits only those). */
INLINE vec3 scene_eval_environment(const SceneData* sd, vec3 d) {
    uint n = N_INFINITE(sd);
    vec3 L = v3s(0.0f);
    EmitterQuery q;
    q.wi = d;  /* all an infinite emitter's eval reads */
    for (uint i = 0u; i < n; ++i) L = vadd(L, emitter_row_eval(sd, &sd->emitters[sd->infinite[i]], &q));
    return L;
}

/* Light-selection pdf of an escaping direction: sum over infinite emitters of P(e) pdf_e(d). */
INLINE float scene_environment_pdf(const SceneData* sd, vec3 d) {
    uint n = N_INFINITE(sd);
    float pdf = 0.0f;
    EmitterQuery q;
    q.wi = d;  /* all an infinite emitter's pdf reads */
    for (uint i = 0u; i < n; ++i) {
        uint e = sd->infinite[i];
        float prob = scene_emitter_prob(sd, e);
        if (prob > 0.0f) pdf += emitter_row_pdf(sd, &sd->emitters[e], &q) * prob;
    }
    return pdf;
}

/* Radiance leaving the hit surface toward the viewer (wo_world points at the viewer); 0 if the shape does
   not emit or wo is on the back of its shading normal. */
INLINE vec3 area_emitter_Le(const SceneData* sd, const Intersection* its, vec3 wo_world) {
    uint e = sd->shapes[its->shape].emitter;
    if (e == NONE) return v3s(0.0f);
    __global const Emitter* em = &sd->emitters[e];
    if (!(em->flags & EMITTER_SURFACE)) return v3s(0.0f);
    EmitterQuery q;
    q.n = its->sh.n;
    q.wi = vneg(wo_world);
    q.uv = its->uv;
    return emitter_row_eval(sd, em, &q);
}

#endif
