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

/* The state of one path between its stages. The megakernel (path_loop.h) runs the stages in a loop per work-item;
   the wavefront driver (kernels/wavefront.cl) keeps PathStates in a device buffer and runs each stage as a kernel of
   its own over the paths that need it, with these very functions. Flags are uints: the struct lives in __global
   memory there, where OpenCL C allows no bool. The host learns its size from the device (wavefront.cl's
   wf_sizes), so nothing else spells out its layout. */
typedef struct {
    Ray ray;            /* the segment to trace next */
    Ray shadow;         /* the shadow ray of a pending emitter sample (shadow_pending) */
    vec3 L;             /* radiance gathered so far */
    vec3 beta;          /* path throughput */
    vec3 prev_p;        /* where `ray` starts */
    vec3 shadow_L;      /* what the pending emitter sample adds to L if `shadow` is not blocked */
    float eta;          /* product of the relative IORs crossed (Russian roulette uses beta * eta^2) */
    float prev_pdf;     /* solid-angle pdf of the BSDF sample that made `ray` */
    uint depth;         /* segments traced so far */
    uint after_delta;   /* `ray` left a delta BSDF (or is the camera ray): only BSDF sampling finds its emission */
    uint alive;         /* `ray` is still to be traced */
    uint shadow_pending;
    uint valid;         /* Mitsuba's path: whether the sample keeps what it gathered (path_mitsuba.h) */
    vec3 chan_pdf;      /* volpath in media: the path's free-flight density had each channel been the hero, over
                           their mean (media.h) */
    uint medium;        /* the medium `ray` travels in (a row of `media`; NONE: vacuum; volpath, media.h) */
    uint shadow_medium; /* the medium `shadow` starts in */
    uint hero;          /* the channel whose extinction samples the path's free flights (3: not chosen yet) */
} PathState;

/* Stage 0: a camera ray. */
INLINE void path_begin(const SceneData* sd, PathState* ps, Ray ray) {
    ps->ray = ray;
    ps->L = v3s(0.0f);
    ps->beta = v3s(1.0f);
    ps->eta = 1.0f;
    ps->prev_pdf = 0.0f;
    ps->prev_p = ray.o;
    ps->depth = 0u;
    ps->after_delta = 1u;   /* the camera ray counts as "delta": nothing else can find what it sees */
    ps->alive = 1u;
    ps->shadow_pending = 0u;
    ps->valid = 1u;
    ps->medium = sd->info->camera_medium;
    ps->shadow_medium = NONE;
    ps->chan_pdf = v3s(1.0f);
    ps->hero = 3u;
#if defined(PATH_MITSUBA)
    ps->valid = sd->info->n_infinite > 0u || sd->info->p.path_mitsuba.volpath != 0u;
    if (sd->info->max_depth == 0u) { ps->alive = 0u; ps->valid = 0u; }   /* Mitsuba: max_depth 0 renders nothing */
#endif
}

/* Stage 1, after the trace (`hit`: a surface at `its`): add the emission the segment reaches, MIS-weighted against
   emitter sampling at the previous vertex. Returns whether the path goes on from `its` (it ends on a miss, and at
   max_depth unless `no_limit`: Mitsuba's volpath decides at its next BSDF sample, path_mitsuba.h). */
INLINE bool path_emission(const SceneData* sd, PathState* ps, bool hit, const Intersection* its, bool no_limit) {
    vec3 le = hit ? hit_emission(sd, its, ps->ray.d) : escaped(sd, ps->ray.d);
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
        ps->L = vadd(ps->L, vscale(vmul(ps->beta, le), w));
    }
    if (!hit || (!no_limit && ps->depth + 1u >= sd->info->max_depth)) ps->alive = 0u;
    return ps->alive != 0u;
}

/* Stage 2: emitter sampling at a non-delta vertex (path_ems, path_mis, Mitsuba's path). Its shadow ray is left
   pending (path_shadow_done adds the sample once the ray is traced). */
INLINE void path_sample_lights(const SceneData* sd, PathState* ps, const Intersection* its, __global const Bsdf* b,
                               Sampler* smp) {
#if defined(PATH_USE_EMS)
    if (PATH_SAMPLES_LIGHTS(b) && ps->depth + 2u <= sd->info->max_depth) {
        vec3 wi = to_local(&its->sh, vneg(ps->ray.d));
#if defined(PATH_USE_MATS)
        vec3 c = sample_light_unshadowed(sd, its, b, wi, smp, true, &ps->shadow);
#else
        vec3 c = sample_light_unshadowed(sd, its, b, wi, smp, false, &ps->shadow);
#endif
        if (!is_black(c)) {
            ps->shadow_L = vmul(ps->beta, c);
            ps->shadow_pending = 1u;
        }
    }
#endif
}

/* Stage 2b: the pending emitter sample counts unless its shadow ray was blocked. */
INLINE void path_shadow_done(PathState* ps, bool occluded) {
    if (ps->shadow_pending && !occluded) ps->L = vadd(ps->L, ps->shadow_L);
    ps->shadow_pending = 0u;
}

/* Stage 2b with media (kernels/integrators/media.h): the pending sample times its shadow ray's transmittance. */
INLINE void path_shadow_through(PathState* ps, vec3 transmittance) {
    if (ps->shadow_pending) ps->L = vadd(ps->L, vmul(ps->shadow_L, transmittance));
    ps->shadow_pending = 0u;
}

#if defined(PATH_MITSUBA)
/* Mitsuba's roulette, after a scattering event (a BSDF's or, in volpath, a medium's) once depth reaches rr_depth. */
INLINE void path_roulette_mitsuba(const SceneData* sd, PathState* ps, Sampler* smp) {
    if (ps->depth >= sd->info->rr_depth) {
        float q = minf(max3(ps->beta) * ps->eta * ps->eta, 0.95f);
        if (!(next1d(smp) < q)) { ps->alive = 0u; return; }
        ps->beta = vdivs(ps->beta, q);
    }
}
#endif

/* Stage 3: Russian roulette as Nori's, then the BSDF sample that makes the next segment (Mitsuba: the sample, then
   the roulette, from the depth counted after it). */
INLINE void path_continue(const SceneData* sd, PathState* ps, const Intersection* its, __global const Bsdf* b,
                          Sampler* smp) {
#if !defined(PATH_MITSUBA)
    if (ps->depth >= sd->info->rr_depth) {
        float q = minf(max3(ps->beta) * ps->eta * ps->eta, 0.99f);
        if (!(next1d(smp) < q)) { ps->alive = 0u; return; }
        ps->beta = vdivs(ps->beta, q);
    }
#endif
    BsdfQuery bq = bsdf_query(sd, its, vneg(ps->ray.d));
    vec3 w = bsdf_sample(b, &bq, next2d(smp));
    if (is_black(w)) { ps->alive = 0u; return; }
    ps->beta = vmul(ps->beta, w);
    ps->eta *= bq.eta;
    ps->after_delta = bq.measure == MEASURE_DISCRETE;
    ps->prev_pdf = ps->after_delta ? 0.0f : bsdf_pdf(b, &bq);
    ps->prev_p = its->p;
    ps->ray = spawn_ray_from(its, to_world(&its->sh, bq.wo));
    ps->depth += 1u;
#if defined(PATH_MITSUBA)
    path_roulette_mitsuba(sd, ps, smp);
#endif
}

#if !defined(PATH_MITSUBA)
/* One vertex of Nori's path family, after its segment was traced (`traced`: the BVH hit `h`): emission, emitter
   sample, roulette and BSDF sample, in the order the megakernel has always drawn their random numbers. */
INLINE void path_vertex(const SceneData* sd, PathState* ps, bool traced, const Hit* h, Sampler* smp) {
    Intersection its;
    bool hit = traced && scene_surface(sd, &ps->ray, h, &its);
    if (!path_emission(sd, ps, hit, &its, false)) return;
    __global const Bsdf* b = bsdf_at(sd, &its);
    path_sample_lights(sd, ps, &its, b, smp);
    path_continue(sd, ps, &its, b, smp);
}

INLINE vec3 path_result(const SceneData* sd, const PathState* ps) { return ps->L; }

#include "path_loop.h"
#endif
