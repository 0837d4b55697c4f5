/* The path tracing loop shared by path_mats, path_ems and path_mis. The including file defines
   PATH_USE_EMS (emitter sampling at non-delta vertices) and PATH_USE_MATS (emission found by BSDF
   sampling after non-delta vertices); with both, the two are combined by the balance heuristic.
   Whatever the strategy, emission is always counted for the camera ray and after delta bounces, where
   only BSDF sampling can find it, and never twice.
   Russian roulette as Nori: from depth rr_depth (3) on, continue with q = min(max(throughput) eta², 0.99).
   max_depth (SceneInfo) limits the number of path segments (1 = emitters seen directly), default none.
   Mitsuba's `path` (path_mitsuba.h) uses the same stages with PATH_MITSUBA defined: the power heuristic
   (LIGHTING_MIS), emitter sampling at every smooth BSDF (bsdf_is_smooth, which includes the smooth lobes of mixed
   BSDFs) and Mitsuba's roulette (after the BSDF sample, on the new throughput and depth, capped at 0.95). */
#if defined(PATH_MITSUBA)
#define LIGHTING_MIS mis_power
#define PATH_SAMPLES_LIGHTS(b) bsdf_is_smooth(b)
#else
#define PATH_SAMPLES_LIGHTS(b) (!bsdf_is_delta(b))
#endif
#include "lighting.h"

/* The state of one path between its stages. The megakernel below runs the stages in a loop per work-item (the
   right shape for PoCL); a wavefront driver for GPUs can keep PathStates in a buffer and run each stage as its
   own kernel over the paths that need it, with the same stage functions. */
typedef struct {
    Ray ray;            /* the segment to trace next */
    float3 L;           /* radiance gathered so far */
    float3 beta;        /* path throughput */
    float eta;          /* product of the relative IORs crossed (Russian roulette uses beta * eta^2) */
    float prev_pdf;     /* solid-angle pdf of the BSDF sample that made `ray` */
    float3 prev_p;      /* where `ray` starts */
    uint depth;         /* segments traced so far */
    bool after_delta;   /* `ray` left a delta BSDF (or is the camera ray): only BSDF sampling finds its emission */
    bool alive;
} PathState;

/* Stage 0: a camera ray. */
INLINE void path_begin(PathState* ps, Ray ray) {
    ps->ray = ray;
    ps->L = (float3)(0.0f);
    ps->beta = (float3)(1.0f);
    ps->eta = 1.0f;
    ps->prev_pdf = 0.0f;
    ps->prev_p = ray.o;
    ps->depth = 0u;
    ps->after_delta = true;   /* the camera ray counts as "delta": nothing else can find what it sees */
    ps->alive = true;
}

/* Stage 1: trace the segment and add the emission it reaches, MIS-weighted against emitter sampling at the
   previous vertex. Returns whether it hit a surface (the path ends otherwise, or at max_depth unless
   `no_limit`: Mitsuba's volpath decides at its next BSDF sample, path_mitsuba.h). */
INLINE bool path_intersect_limited(const SceneData* sd, PathState* ps, Intersection* its, bool no_limit) {
    bool hit = scene_intersect(sd, &ps->ray, its);
    float3 le = hit ? hit_emission(sd, its, ps->ray.d) : escaped(sd, ps->ray.d);
    if (!is_black(le)) {
        float w;
        if (ps->after_delta) w = 1.0f;
#if defined(PATH_USE_MATS) && defined(PATH_USE_EMS)
        else w = LIGHTING_MIS(ps->prev_pdf, hit ? hit_emitter_pdf(sd, ps->prev_p, its)
                                                : scene_environment_pdf(sd, ps->ray.d));
#elif defined(PATH_USE_MATS)
        else w = 1.0f;
#else
        else w = 0.0f;
#endif
        ps->L += ps->beta * le * w;
    }
    if (!hit || (!no_limit && ps->depth + 1u >= sd->info->max_depth)) ps->alive = false;
    return ps->alive;
}

INLINE bool path_intersect(const SceneData* sd, PathState* ps, Intersection* its) {
    return path_intersect_limited(sd, ps, its, false);
}

/* Stage 2: emitter sampling at a non-delta vertex (path_ems, path_mis, Mitsuba's path). */
INLINE void path_sample_lights(const SceneData* sd, PathState* ps, const Intersection* its, __global const Bsdf* b,
                               Sampler* smp) {
#if defined(PATH_USE_EMS)
    if (PATH_SAMPLES_LIGHTS(b) && ps->depth + 2u <= sd->info->max_depth) {
        float3 wi = to_local(&its->sh, -ps->ray.d);
#if defined(PATH_USE_MATS)
        ps->L += ps->beta * sample_light(sd, its, b, wi, smp, true);
#else
        ps->L += ps->beta * sample_light(sd, its, b, wi, smp, false);
#endif
    }
#endif
}

/* Stage 3: Russian roulette as Nori's, then the BSDF sample that makes the next segment (Mitsuba: the sample, then
   the roulette, from the depth counted after it). */
INLINE void path_continue(const SceneData* sd, PathState* ps, const Intersection* its, __global const Bsdf* b,
                          Sampler* smp) {
#if !defined(PATH_MITSUBA)
    if (ps->depth >= sd->info->rr_depth) {
        float q = minf(max3(ps->beta) * ps->eta * ps->eta, 0.99f);
        if (!(next1d(smp) < q)) { ps->alive = false; return; }
        ps->beta /= q;
    }
#endif
    BsdfQuery bq = bsdf_query(sd, its, -ps->ray.d);
    float3 w = bsdf_sample(b, &bq, next2d(smp));
    if (is_black(w)) { ps->alive = false; return; }
    ps->beta *= w;
    ps->eta *= bq.eta;
    ps->after_delta = bq.measure == MEASURE_DISCRETE;
    ps->prev_pdf = ps->after_delta ? 0.0f : bsdf_pdf(b, &bq);
    ps->prev_p = its->p;
    ps->ray = spawn_ray_from(its, to_world(&its->sh, bq.wo));
    ps->depth += 1u;
#if defined(PATH_MITSUBA)
    if (ps->depth >= sd->info->rr_depth) {
        float q = minf(max3(ps->beta) * ps->eta * ps->eta, 0.95f);
        if (!(next1d(smp) < q)) { ps->alive = false; return; }
        ps->beta /= q;
    }
#endif
}

/* The megakernel: the stages in a loop. The random numbers are drawn in the same order as before the stages
   were split out (emitter sample, roulette, BSDF sample per vertex), so images are unchanged. Mitsuba's path
   has a loop of its own (path_mitsuba.h). */
#if !defined(PATH_MITSUBA)
INLINE float3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    PathState ps;
    path_begin(&ps, ray);
    for (;;) {
        Intersection its;
        if (!path_intersect(sd, &ps, &its)) break;
        __global const Bsdf* b = bsdf_at(sd, &its);
        path_sample_lights(sd, &ps, &its, b, smp);
        path_continue(sd, &ps, &its, b, smp);
        if (!ps.alive) break;
    }
    return ps.L;
}
#endif
