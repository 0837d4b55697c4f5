/* Participating media for Mitsuba's volpath (path_mitsuba.h, built with CLR_MEDIA when the scene packs media):
   free flights in the medium a path travels in, scattering by the medium's phase function (emitter sampling with
   its MIS weight, then a phase sample), medium changes where a path crosses a shape with interior/exterior media,
   and the transmittance of shadow rays through media and pass-through surfaces.

   In a homogeneous medium free flights and transmittance are closed forms. With an extinction that differs between
   channels, sampling every flight with one channel's exponential and weighting by it alone (Mitsuba's volpath)
   weights the other channels by exp((s_c - s_k) t) per flight, unbounded. Here a hero channel is picked uniformly
   per path, its extinction samples every flight, and the path is weighted by the mean of the densities the whole
   path would have had under each channel (one-sample MIS with the balance heuristic over the three channels,
   spectral MIS as Mitsuba's volpathmis): each channel's weight stays within 3 times its albedo's product. (Weighting
   each flight by the mixture of that flight's densities alone is not enough: its ratios, up to 3 each, multiply
   along a path; the furnace test saw them.)

   A heterogeneous medium (flag HOMOGENEOUS unset) is tracked against its majorant mu (kernels/media/tracking.h):
   tentative collisions at rate mu, each a real one with probability sigma_t/mu of the hero channel, else a null one
   (delta tracking, as Mitsuba's volpath, which re-traces from each null collision; here the loop goes on along the
   same ray). The same spectral MIS weights them: a real collision has density sigma_t,c / mu in channel c and value
   sigma_s,c / mu, a null one density and value (mu - sigma_t,c) / mu, the flight's exp(-mu t) being the same in
   every channel. Shadow rays take the transmittance by ratio tracking. Null collisions do not count toward
   max_depth (Mitsuba's count only real ones); MEDIA_MAX_NULL_COLLISIONS bounds the loops.

   As Mitsuba's volpath: a scattering event in a medium counts toward max_depth as a bounce does; shadow rays cross
   surfaces by what their BSDF lets straight through (bsdf_null_transmission, Mitsuba's eval_null_transmission:
   null, a mask's transparent part, a thindielectric's 1 - R, a blend's) and are blocked by every other one, a
   dielectric included; a light found through such a pass-through is weighted by MIS against the emitter sample of
   the last real scattering event (the pass-through changes neither the vertex nor the pdf MIS compares with). A
   path's own pass-through at a surface whose null transmission is 0 counts as a delta event instead: no shadow ray
   crosses it there, so only the path can find what lies behind. */
#ifndef CLRENDER_INTEGRATORS_MEDIA_H
#define CLRENDER_INTEGRATORS_MEDIA_H
#include "gen/medium_dispatch.h"
#include "gen/phase_dispatch.h"
#include "media/tracking.h"

/* A shadow ray's pass-throughs: beyond this many surfaces it counts as blocked (a bound on the loop, far above any
   real stack of null surfaces). */
#define MEDIA_MAX_CROSSINGS 64

/* exp(-sigma d) per channel; 1 where sigma is 0 (also over an infinite distance). */
INLINE vec3 medium_transmittance(vec3 sigma, float d) {
    return v3(sigma.x > 0.0f ? exp(-sigma.x * d) : 1.0f, sigma.y > 0.0f ? exp(-sigma.y * d) : 1.0f,
              sigma.z > 0.0f ? exp(-sigma.z * d) : 1.0f);
}

/* The medium a ray leaving the surface `its` along d travels in: the shape's exterior on the side its geometric
   normal points to, its interior on the other (Mitsuba's target_medium); a shape with neither is no medium boundary
   and `current` goes on. */
INLINE uint medium_across(const SceneData* sd, const Intersection* its, vec3 d, uint current) {
    __global const Shape* s = &sd->shapes[its->shape];
    if (s->interior == NONE && s->exterior == NONE) return current;
    return dot3(d, its->ng) > 0.0f ? s->exterior : s->interior;
}

/* The transmittance along a shadow ray that starts in `medium`: each segment's transmittance in the medium it
   crosses (exp(-sigma_t length) in a homogeneous one, ratio tracking in the others), times the null transmission
   of every surface on the way (0 at any other surface). */
INLINE vec3 shadow_transmittance(const SceneData* sd, const Ray* shadow, uint medium, Sampler* smp) {
    if (!(shadow->tmax > 0.0f)) return v3s(1.0f);
    Ray r = *shadow;
    vec3 tr = v3s(1.0f);
    for (int i = 0; i < MEDIA_MAX_CROSSINGS; ++i) {
        Hit h;
        Intersection its;
        bool hit = scene_trace(sd, &r, &h) && scene_surface(sd, &r, &h, &its);
        if (medium != NONE) {
            __global const Medium* m = sd->media + medium;
            float len = hit ? its.t : r.tmax;
            tr = vmul(tr, (m->flags & MEDIUM_HOMOGENEOUS) != 0u
                              ? medium_transmittance(medium_sigma_t(sd, m, r.o), len)
                              : medium_ratio_tracking(sd, m, r.o, r.d, len, smp));
        }
        if (!hit || is_black(tr)) return tr;
        BsdfQuery q = bsdf_query(sd, &its, vneg(r.d));
        tr = vmul(tr, bsdf_null_transmission(bsdf_at(sd, &its), &q));
        if (is_black(tr)) return tr;
        medium = medium_across(sd, &its, r.d, medium);
        Ray next = spawn_ray_from(&its, r.d);
        next.tmax = r.tmax - len3(vsub(next.o, r.o));
        if (!(next.tmax > 0.0f)) return tr;
        r = next;
    }
    return v3s(0.0f);
}

/* A scattering vertex at p in medium row m: depth, emitter sampling (its shadow ray left pending, from the medium),
   the phase sample that makes the next segment, and Mitsuba's roulette. */
INLINE void medium_scatter(const SceneData* sd, PathState* ps, __global const Medium* m, vec3 p, Sampler* smp) {
    ps->depth += 1u;
    if (ps->depth >= sd->info->max_depth) { ps->alive = 0u; return; }
    __global const Phase* ph = sd->phases + m->phase;
    PhaseQuery pq;
    pq.wi = vneg(ps->ray.d);
    if ((m->flags & MEDIUM_SAMPLE_EMITTERS) != 0u) {
        EmitterQuery q;
        q.ref = p;
        float a = next1d(smp);
        float2 u = next2d(smp);
        vec3 le = scene_sample_emitter(sd, &q, v3(a, u.x, u.y));
        if (!is_black(le) && q.pdf > 0.0f) {
            pq.wo = q.wi;
            float f = phase_eval(ph, &pq);
            float w = q.delta ? 1.0f : LIGHTING_MIS(q.pdf, f);
            if (f > 0.0f) {
                ps->shadow = shadow_ray_from(p, &q);
                ps->shadow_L = vmul(ps->beta, vscale(le, f * w));
                ps->shadow_medium = ps->medium;
                ps->shadow_pending = 1u;
            }
        }
    }
    float weight = phase_sample(ph, &pq, next2d(smp));
    if (!(pq.pdf > 0.0f) || !(weight > 0.0f)) { ps->alive = 0u; return; }
    ps->beta = vscale(ps->beta, weight);
    /* a medium that samples no emitters leaves the phase sample the only way to its light: what it finds counts
       whole, as after a delta BSDF (Mitsuba's volpath puts such a vertex into its specular chain) */
    ps->after_delta = (m->flags & MEDIUM_SAMPLE_EMITTERS) == 0u;
    ps->prev_pdf = pq.pdf;
    ps->prev_p = p;
    ps->ray.o = p;
    ps->ray.d = pq.wo;
    ps->ray.tmin = 0.0f;
    ps->ray.tmax = INFINITY;
    path_roulette_mitsuba(sd, ps, smp);
}

/* One event of a free flight under the spectral MIS: `density` is each channel's density of it, `value` what it
   contributes; the throughput gets value over the mean of the channels' path densities (chan_pdf keeps them
   relative to that mean). False if that ends the path. */
INLINE bool medium_weigh(PathState* ps, vec3 density, vec3 value) {
    vec3 pdf = vmul(ps->chan_pdf, density);
    float mean = (pdf.x + pdf.y + pdf.z) * (1.0f / 3.0f);
    if (!(mean > 0.0f) || !isfinite(mean)) { ps->alive = 0u; return false; }
    ps->chan_pdf = vscale(pdf, 1.0f / mean);
    ps->beta = vmul(ps->beta, vscale(value, 1.0f / mean));
    return true;
}

/* Delta tracking through the heterogeneous medium m from the ray's tmin to tmax (see the top of this file). */
INLINE bool medium_flight_tracked(const SceneData* sd, PathState* ps, __global const Medium* m, float tmax,
                                  Sampler* smp) {
    float t = ps->ray.tmin, t1 = tmax;
    float mu = medium_track_range(sd, m, ps->ray.o, ps->ray.d, &t, &t1);
    if (mu == 0.0f) return false;
    vec3 sigma;
    bool real;
    for (int i = 0; i < MEDIA_MAX_NULL_COLLISIONS; ++i) {
        if (!medium_track_step(sd, m, ps->ray.o, ps->ray.d, mu, t1, ps->hero, smp, &t, &sigma, &real)) return false;
        vec3 p = vmad(ps->ray.d, t, ps->ray.o);
        vec3 density = real ? sigma : vsub(v3s(mu), sigma);
        if (!medium_weigh(ps, density, real ? vmul(sigma, medium_albedo(sd, m, p)) : density)) return true;
        if (real) {
            if (is_black(ps->beta)) { ps->alive = 0u; return true; }
            medium_scatter(sd, ps, m, p, smp);
            return true;
        }
    }
    ps->alive = 0u;
    return true;
}

/* The free flight of the segment just traced, in the path's medium (the surface at `tmax`, or none). Returns true
   if the medium took the path (a scattering vertex, or the end of the path); false if it reaches the surface (or
   escapes). The flight is sampled with the hero channel's extinction (or tracked against the majorant) and
   weighted by medium_weigh. */
INLINE bool medium_flight(const SceneData* sd, PathState* ps, float tmax, Sampler* smp) {
    __global const Medium* m = sd->media + ps->medium;
    if (ps->hero > 2u) ps->hero = min((uint)(next1d(smp) * 3.0f), 2u);
    if ((m->flags & MEDIUM_HOMOGENEOUS) == 0u) return medium_flight_tracked(sd, ps, m, tmax, smp);
    vec3 sigma = medium_sigma_t(sd, m, ps->ray.o);
    float sc = vchannel(sigma, ps->hero);
    /* the medium starts where the ray does: at tmin (a camera ray's near clip plane, where Mitsuba's start) */
    float t0 = ps->ray.tmin;
    float t = t0 + (sc > 0.0f ? -log(1.0f - next1d(smp)) / sc : INFINITY);
    bool scatter = t < tmax;
    vec3 tr = medium_transmittance(sigma, (scatter ? t : tmax) - t0);
    vec3 density = scatter ? vmul(sigma, tr) : tr;   /* each channel's density of this event */
    vec3 p = vmad(ps->ray.d, scatter ? t : t0, ps->ray.o);
    vec3 value = scatter ? vmul(tr, vmul(sigma, medium_albedo(sd, m, p))) : tr;   /* (an albedo volume: at p) */
    if (!medium_weigh(ps, density, value)) return true;
    if (!scatter) return false;
    if (is_black(ps->beta)) { ps->alive = 0u; return true; }
    medium_scatter(sd, ps, m, p, smp);
    return true;
}

#endif
