/* The path tracing loop shared by path_mats, path_ems and path_mis. The including file defines
   PATH_USE_EMS (emitter sampling at non-delta vertices) and PATH_USE_MATS (emission found by BSDF
   sampling after non-delta vertices); with both, the two are combined by the balance heuristic.
   Whatever the strategy, emission is always counted for the camera ray and after delta bounces, where
   only BSDF sampling can find it, and never twice.
   Russian roulette as Nori: from depth rr_depth (3) on, continue with q = min(max(throughput) eta², 0.99).
   max_depth (SceneInfo) limits the number of path segments (1 = emitters seen directly), default none. */
#include "lighting.h"

INLINE float3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    float3 L = (float3)(0.0f);
    float3 beta = (float3)(1.0f);
    float eta = 1.0f;
    bool after_delta = true;   /* the camera ray counts as "delta": nothing else can find what it sees */
    float prev_pdf = 0.0f;     /* solid-angle pdf of the BSDF sample that made this ray */
    float3 prev_p = ray.o;
    uint max_depth = sd->info->max_depth, rr_depth = sd->info->rr_depth;
    for (uint depth = 0u;; ++depth) {
        Intersection its;
        bool hit = scene_intersect(sd, &ray, &its);
        /* Emission reached by this ray. */
        float3 le = hit ? hit_emission(sd, &its, ray.d) : escaped(sd, ray.d);
        if (!is_black(le)) {
            float w;
            if (after_delta) w = 1.0f;
#if defined(PATH_USE_MATS) && defined(PATH_USE_EMS)
            else w = mis_balance(prev_pdf, hit ? hit_emitter_pdf(sd, prev_p, &its) : scene_environment_pdf(sd, ray.d));
#elif defined(PATH_USE_MATS)
            else w = 1.0f;
#else
            else w = 0.0f;
#endif
            L += beta * le * w;
        }
        if (!hit || depth + 1u >= max_depth) break;

        __global const Bsdf* b = bsdf_at(sd, &its);
        bool delta = bsdf_is_delta(b);
        float3 wi = to_local(&its.sh, -ray.d);
#if defined(PATH_USE_EMS)
        if (!delta && depth + 2u <= max_depth) {
#if defined(PATH_USE_MATS)
            L += beta * sample_light(sd, &its, b, wi, smp, true);
#else
            L += beta * sample_light(sd, &its, b, wi, smp, false);
#endif
        }
#endif
        if (depth >= rr_depth) {
            float q = minf(max3(beta) * eta * eta, 0.99f);
            if (!(next1d(smp) < q)) break;
            beta /= q;
        }
        BsdfQuery bq = bsdf_query(&its, -ray.d);
        float3 w = bsdf_sample(b, &bq, next2d(smp));
        if (is_black(w)) break;
        beta *= w;
        eta *= bq.eta;
        after_delta = bq.measure == MEASURE_DISCRETE;
        prev_pdf = after_delta ? 0.0f : bsdf_pdf(b, &bq);
        prev_p = its.p;
        ray = spawn_ray_from(&its, to_world(&its.sh, bq.wo));
    }
    return L;
}
