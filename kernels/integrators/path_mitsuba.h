/* Mitsuba 3's `path` (clrender/integrators/path.py): emitter sampling and BSDF sampling at every vertex, combined
   by the power heuristic; max_depth counts segments (1 = emitters seen directly, 2 = direct illumination);
   Russian roulette from rr_depth (p.path_mitsuba: hide_emitters). The stages are path.h's. */
#define PATH_USE_EMS
#define PATH_USE_MATS
#define PATH_MITSUBA
#include "path.h"

INLINE float3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    if (sd->info->max_depth == 0u) return (float3)(0.0f);   /* Mitsuba: max_depth 0 renders nothing */
    PathState ps;
    path_begin(&ps, ray);
    for (;;) {
        Intersection its;
        if (ps.depth == 0u && sd->info->p.path_mitsuba.hide_emitters != 0u) {
            /* Hidden emitters: the camera ray sees neither emitter shapes nor the environment. */
            if (!scene_intersect_hiding_emitters(sd, &ps.ray, &its) || sd->info->max_depth == 1u) break;
        } else if (!path_intersect(sd, &ps, &its)) {
            break;
        }
        __global const Bsdf* b = bsdf_at(sd, &its);
        path_sample_lights(sd, &ps, &its, b, smp);
        path_continue(sd, &ps, &its, b, smp);
        if (!ps.alive) break;
    }
    return ps.L;
}
