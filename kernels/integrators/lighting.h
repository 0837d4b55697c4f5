/* What the illumination integrators share: emission seen at a hit, one emitter sample with its shadow
   ray, and the MIS weights (balance heuristic). Every integrator below is a loop over path vertices with
   its state in locals: no recursion, so the same stage functions can serve a wavefront variant later. */
#ifndef CLRENDER_LIGHTING_H
#define CLRENDER_LIGHTING_H
#include "../warp.h"
#include "../bsdf.h"
#include "../emitter.h"

INLINE __global const Bsdf* bsdf_at(const SceneData* sd, const Intersection* its) {
    return sd->bsdfs + sd->shapes[its->shape].bsdf;
}

INLINE float mis_balance(float a, float b) { return a + b > 0.0f ? a / (a + b) : 0.0f; }

/* The power heuristic (exponent 2), Mitsuba's: 0 where the ratio is not finite (both pdfs 0, or overflow). */
INLINE float mis_power(float a, float b) {
    float a2 = a * a, w = a2 / (a2 + b * b);
    return isfinite(w) ? w : 0.0f;
}

/* The MIS heuristic of sample_light and the path loop: an integrator may define it before including this file. */
#ifndef LIGHTING_MIS
#define LIGHTING_MIS mis_balance
#endif

/* Mitsuba's "smooth" BSDFs (a diffuse or glossy lobe, or no lobe flags at all: anything not purely delta):
   the ones emitter sampling can serve. */
INLINE bool bsdf_is_smooth(__global const Bsdf* b) {
    return (b->flags & (BSDF_DIFFUSE | BSDF_GLOSSY)) != 0u || (b->flags & BSDF_DELTA) == 0u;
}

INLINE BsdfQuery bsdf_query(const SceneData* sd, const Intersection* its, vec3 wi_world) {
    BsdfQuery q;
    q.textures = sd->textures;
    q.tables = sd->bsdf_tables;
    q.wi = to_local(&its->sh, wi_world);
    q.wo = v3s(0.0f);
    q.eta = 1.0f;
    q.measure = MEASURE_SOLID_ANGLE;
    q.uv = its->uv;
#ifdef CLR_SURFACE_DERIVATIVES
    q.dpdu = to_local(&its->sh, its->dpdu);
    q.dpdv = to_local(&its->sh, its->dpdv);
    q.ng = to_local(&its->sh, its->ng);
    q.dpdu_world = its->dpdu;
#endif
    return q;
}

/* Radiance an emitter sends from the hit `its` back along -d (0 if the surface does not emit). */
INLINE vec3 hit_emission(const SceneData* sd, const Intersection* its, vec3 d) {
    if (sd->shapes[its->shape].emitter == NONE) return v3s(0.0f);
    return area_emitter_Le(sd, its, vneg(d));
}

/* The light-selection pdf of having reached emitter hit `its` from `ref` (for MIS of BSDF samples). */
INLINE float hit_emitter_pdf(const SceneData* sd, vec3 ref, const Intersection* its) {
    uint e = sd->shapes[its->shape].emitter;
    if (e == NONE) return 0.0f;
    EmitterQuery q;
    emitter_query_from_hit(&q, ref, its);
    return scene_emitter_pdf(sd, e, &q);
}

/* The shadow ray of an emitter sample q->p (or toward q->wi, for lights at infinity) from o: it aims at q->p,
   stopping short of the light's own surface. A segment too short to hold anything gets tmax <= 0: nothing can block
   it (shadow_occluded). From the hit `its`, it starts off the surface (spawn_origin). */
INLINE Ray shadow_ray_from(vec3 o, const EmitterQuery* q) {
    Ray r;
    r.o = o;
    r.tmin = 0.0f;
    if (!isfinite(q->dist)) {
        r.d = q->wi;
        r.tmax = INFINITY;
        return r;
    }
    vec3 d = vsub(q->p, r.o);
    float len = len3(d);
    r.d = vscale(d, 1.0f / len);
    r.tmax = len * (1.0f - 1e-4f) - ray_eps(q->p);
    return r;
}

INLINE Ray light_shadow_ray(const Intersection* its, const EmitterQuery* q) {
    return shadow_ray_from(spawn_origin(its, q->wi), q);
}

INLINE bool shadow_occluded(const SceneData* sd, const Ray* r) {
    if (!(r->tmax > 0.0f)) return false;
    return scene_occluded(sd, r->o, r->d, 0.0f, r->tmax);
}

/* Does anything block the segment from the hit `its` to the light point of q? */
INLINE bool light_occluded(const SceneData* sd, const Intersection* its, const EmitterQuery* q) {
    Ray r = light_shadow_ray(its, q);
    return shadow_occluded(sd, &r);
}

/* One emitter sample at a non-delta vertex, up to its visibility: f * cos * Le / pdf, times the MIS weight
   (LIGHTING_MIS) against BSDF sampling when `mis` (delta lights always get full weight: BSDF sampling cannot find
   them), and the shadow ray that decides whether it counts. 0 (and no ray to trace) when it cannot contribute. The
   trace is the caller's, so that a wavefront driver can run all shadow rays in a kernel of their own. */
INLINE vec3 sample_light_unshadowed(const SceneData* sd, const Intersection* its, __global const Bsdf* b,
                                    vec3 wi_local, Sampler* smp, bool mis, Ray* shadow) {
    EmitterQuery q;
    q.ref = its->p;
    float a = next1d(smp);
    float2 u = next2d(smp);
    vec3 le = scene_sample_emitter(sd, &q, v3(a, u.x, u.y));
    if (is_black(le) || !(q.pdf > 0.0f)) return v3s(0.0f);
    BsdfQuery bq = bsdf_query(sd, its, v3s(0.0f));
    bq.wi = wi_local;
    bq.wo = to_local(&its->sh, q.wi);
    vec3 f = bsdf_eval(b, &bq);
    if (is_black(f)) return v3s(0.0f);
    *shadow = light_shadow_ray(its, &q);
    float w = 1.0f;
    if (mis && !q.delta) w = LIGHTING_MIS(q.pdf, bsdf_pdf(b, &bq));
    vec3 fle = vmul(vscale(f, fabs(bq.wo.z)), le);
    return vscale(fle, w);
}

/* The same with its shadow ray traced. */
INLINE vec3 sample_light(const SceneData* sd, const Intersection* its, __global const Bsdf* b,
                         vec3 wi_local, Sampler* smp, bool mis) {
    Ray shadow;
    vec3 c = sample_light_unshadowed(sd, its, b, wi_local, smp, mis, &shadow);
    if (is_black(c) || shadow_occluded(sd, &shadow)) return v3s(0.0f);
    return c;
}

/* Radiance from the environment (infinite emitters) along an escaping direction d. */
INLINE vec3 escaped(const SceneData* sd, vec3 d) { return scene_eval_environment(sd, d); }

/* A camera ray under Mitsuba's hide_emitters: shapes that carry an area emitter are not there for it (Mitsuba
   3.9 lets the camera see through them, front or back, to what lies behind), so it continues past each such hit;
   every later segment sees them as usual. hidden_emitter_passed: the ray on past the emitter hit `its` (keeping a
   far clip where it was), or false if `its` is no emitter; path_mitsuba.h's camera stage uses it one hit at a
   time. */
INLINE bool hidden_emitter_passed(const SceneData* sd, const Intersection* its, Ray* ray) {
    if (sd->shapes[its->shape].emitter == NONE) return false;
    Ray next = spawn_ray_from(its, ray->d);
    next.tmax = ray->tmax - its->t;
    *ray = next;
    return true;
}

INLINE bool scene_intersect_hiding_emitters(const SceneData* sd, Ray* ray, Intersection* its) {
    for (;;) {
        if (!scene_intersect(sd, ray, its)) return false;
        if (!hidden_emitter_passed(sd, its, ray)) return true;
    }
}

#endif
