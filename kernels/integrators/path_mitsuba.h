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
#ifdef CLR_MEDIA
#include "media.h"
#endif

/* Whether path_continue's sample from direction d (at depth `depth`) was a null event: a discrete sample that goes
   on undeviated (a failed sample is not: depth stays). */
INLINE bool path_null_event(const PathState* ps, uint depth, vec3 d) {
    return ps->depth != depth && ps->after_delta && dot3(ps->ray.d, d) > 1.0f - 1e-6f;
}

/* Mitsuba's path keeps what a path gathered (PathState.valid) only if the scene has an environment or the path met a
   surface that it did not pass straight through (a null BSDF, a mask's transparent part, a thin dielectric's
   transmission: its "null" events); otherwise the pixel sample is 0, even where it passed an emitter (e.g. a light
   with a null BSDF, as Blender's exporter writes them, seen against an empty background). Checked against Mitsuba
   3.9.1. volpath keeps what every path gathered (no valid-ray rule). */
INLINE void path_vertex(const SceneData* sd, PathState* ps, bool traced, const Hit* h, Sampler* smp) {
    Intersection its;
    bool hit = traced && scene_surface(sd, &ps->ray, h, &its);
    bool hide = sd->info->p.path_mitsuba.hide_emitters != 0u;
    if (sd->info->p.path_mitsuba.volpath != 0u) {
#ifdef CLR_MEDIA
        if (ps->medium != NONE && medium_flight(sd, ps, hit ? its.t : ps->ray.tmax, smp)) return;
#endif
        vec3 before = ps->L;
        hit = path_emission(sd, ps, hit, &its, true);
        if (hide && ps->depth == 0u) ps->L = before;
        if (!hit) return;
    } else if (ps->depth == 0u && hide) {
        /* Hidden emitters: the camera ray sees neither emitter shapes nor the environment; Mitsuba 3.9 lets it see
           through emitter shapes, front or back, to what lies behind (the next trace, keeping a far clip where it
           was); every later segment sees them as usual. */
        if (!hit) { ps->alive = 0u; return; }
        if (hidden_emitter_passed(sd, &its, &ps->ray)) return;   /* traced again, past the emitter */
        if (sd->info->max_depth == 1u) { ps->valid = 1u; ps->alive = 0u; return; }
    } else if (!path_emission(sd, ps, hit, &its, false)) {
        if (traced) ps->valid = 1u;   /* a surface at the depth limit counts */
        return;
    }
    __global const Bsdf* b = bsdf_at(sd, &its);
    path_sample_lights(sd, ps, &its, b, smp);
    vec3 d = ps->ray.d;
    uint depth = ps->depth;
#ifdef CLR_MEDIA
    if (ps->shadow_pending) ps->shadow_medium = medium_across(sd, &its, ps->shadow.d, ps->medium);
    uint after_delta = ps->after_delta;
    float prev_pdf = ps->prev_pdf;
    vec3 prev_p = ps->prev_p;
#endif
    path_continue(sd, ps, &its, b, smp);
    bool null_event = path_null_event(ps, depth, d);
    if (sd->info->p.path_mitsuba.volpath != 0u) {
        if (null_event) ps->depth = depth;   /* null events do not count toward max_depth */
        if (ps->depth >= sd->info->max_depth) ps->alive = 0u;
#ifdef CLR_MEDIA
        ps->medium = medium_across(sd, &its, ps->ray.d, ps->medium);
        if (null_event) {
            /* a pass-through that shadow rays cross too (media.h): MIS stays with the last real vertex */
            BsdfQuery q = bsdf_query(sd, &its, vneg(d));
            if (!is_black(bsdf_null_transmission(b, &q))) {
                ps->after_delta = after_delta;
                ps->prev_pdf = prev_pdf;
                ps->prev_p = prev_p;
            }
        }
#endif
    } else if (!null_event) {
        ps->valid = 1u;
    }
}

INLINE vec3 path_result(const SceneData* sd, const PathState* ps) { return ps->valid ? ps->L : v3s(0.0f); }

#include "path_loop.h"
