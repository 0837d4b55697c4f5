/* Mitsuba 3's `path` (clrender/integrators/path.py): emitter sampling and BSDF sampling at every vertex, combined
   by the power heuristic; max_depth counts segments (1 = emitters seen directly, 2 = direct illumination);
   Russian roulette from rr_depth (p.path_mitsuba: hide_emitters, volpath). The stages are path.h's.
   With p.path_mitsuba.volpath set, Mitsuba's `volpath` rules for surfaces: null events (a null BSDF, a mask's
   transparent part, a thin dielectric's transmission) do not count toward max_depth, so a path goes on through
   them at the depth limit; hide_emitters hides the emission that the path meets before its first real bounce,
   and the surfaces there still reflect. */
#define PATH_USE_EMS
#define PATH_USE_MATS
#define PATH_MITSUBA
#include "path.h"

/* Whether path_continue's sample from direction d (at depth `depth`) was a null event: a discrete sample that goes
   on undeviated (a failed sample is not: depth stays). */
INLINE bool path_null_event(const PathState* ps, uint depth, float3 d) {
    return ps->depth != depth && ps->after_delta && dot3(ps->ray.d, d) > 1.0f - 1e-6f;
}

/* Mitsuba's path keeps what a path gathered only if the scene has an environment or the path met a surface that
   it did not pass straight through (a null BSDF, a mask's transparent part, a thin dielectric's transmission: its
   "null" events); otherwise the pixel sample is 0, even where it passed an emitter (e.g. a light with a null BSDF,
   as Blender's exporter writes them, seen against an empty background). Checked against Mitsuba 3.9.1. */
INLINE float3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    if (sd->info->max_depth == 0u) return (float3)(0.0f);   /* Mitsuba: max_depth 0 renders nothing */
    PathState ps;
    path_begin(&ps, ray);
    bool hide = sd->info->p.path_mitsuba.hide_emitters != 0u;
    bool valid = sd->info->n_infinite > 0u;
    if (sd->info->p.path_mitsuba.volpath != 0u) {   /* volpath keeps what every path gathered (no valid-ray rule) */
        for (;;) {
            Intersection its;
            float3 before = ps.L;
            bool hit = path_intersect_limited(sd, &ps, &its, true);
            if (hide && ps.depth == 0u) ps.L = before;
            if (!hit) break;
            __global const Bsdf* b = bsdf_at(sd, &its);
            path_sample_lights(sd, &ps, &its, b, smp);
            float3 d = ps.ray.d;
            uint depth = ps.depth;
            path_continue(sd, &ps, &its, b, smp);
            if (path_null_event(&ps, depth, d)) ps.depth = depth;
            if (!ps.alive || ps.depth >= sd->info->max_depth) break;
        }
        return ps.L;
    }
    for (;;) {
        Intersection its;
        its.t = -1.0f;   /* set on a hit */
        if (ps.depth == 0u && hide) {
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
        if (!path_null_event(&ps, depth, d)) valid = true;
        if (!ps.alive) break;
    }
    return valid ? ps.L : (float3)(0.0f);
}
