/* Mitsuba 3's `path` (clrender/integrators/path.py): emitter sampling and BSDF sampling at every vertex, combined
   by the power heuristic; max_depth counts segments (1 = emitters seen directly, 2 = direct illumination);
   Russian roulette from rr_depth (p.path_mitsuba: hide_emitters). The stages are path.h's. */
#define PATH_USE_EMS
#define PATH_USE_MATS
#define PATH_MITSUBA
#include "path.h"

/* Mitsuba's path keeps what a path gathered only if the scene has an environment or the path met a surface that
   it did not pass straight through (a null BSDF, a mask's transparent part, a thin dielectric's transmission: its
   "null" events); otherwise the pixel sample is 0, even where it passed an emitter (e.g. a light with a null BSDF,
   as Blender's exporter writes them, seen against an empty background). Checked against Mitsuba 3.9.1. */
INLINE float3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    if (sd->info->max_depth == 0u) return (float3)(0.0f);   /* Mitsuba: max_depth 0 renders nothing */
    PathState ps;
    path_begin(&ps, ray);
    bool valid = sd->info->n_infinite > 0u;
    for (;;) {
        Intersection its;
        its.t = -1.0f;   /* set on a hit */
        if (ps.depth == 0u && sd->info->p.path_mitsuba.hide_emitters != 0u) {
            /* Hidden emitters: the camera ray sees neither emitter shapes nor the environment. */
            if (!scene_intersect_hiding_emitters(sd, &ps.ray, &its)) break;
            if (sd->info->max_depth == 1u) { valid = true; break; }
        } else if (!path_intersect(sd, &ps, &its)) {
            valid = valid || its.t >= 0.0f;   /* a surface at the depth limit counts */
            break;
        }
        __global const Bsdf* b = bsdf_at(sd, &its);
        path_sample_lights(sd, &ps, &its, b, smp);
        float3 d = ps.ray.d;
        uint depth = ps.depth;
        path_continue(sd, &ps, &its, b, smp);
        /* a discrete sample that goes on undeviated is a null event (a failed sample is not: depth stays) */
        if (!(ps.depth != depth && ps.after_delta && dot3(ps.ray.d, d) > 1.0f - 1e-6f)) valid = true;
        if (!ps.alive) break;
    }
    return valid ? ps.L : (float3)(0.0f);
}
