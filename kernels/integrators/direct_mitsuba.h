/* Mitsuba 3's `direct` (clrender/integrators/direct.py): at the camera ray's hit, emitter_samples emitter samples
   (at smooth BSDFs) and bsdf_samples BSDF samples, combined by the power heuristic on the pdfs scaled by each
   technique's share of the samples, each sample weighted 1/count (p.direct_mitsuba). As Mitsuba 3.9 does, an
   emitter sample that reaches a delta light (point, spot, directional) gets weight 1, not 1/emitter_samples, so
   such lights count emitter_samples times. */
#include "lighting.h"

INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    uint ne = sd->info->p.direct_mitsuba.emitter_samples, nb = sd->info->p.direct_mitsuba.bsdf_samples;
    bool hide = sd->info->p.direct_mitsuba.hide_emitters != 0u;
    Intersection its;
    bool hit = hide ? scene_intersect_hiding_emitters(sd, &ray, &its) : scene_intersect(sd, &ray, &its);
    if (!hit) return hide ? v3s(0.0f) : escaped(sd, ray.d);
    vec3 L = hide ? v3s(0.0f) : hit_emission(sd, &its, ray.d);
    __global const Bsdf* b = bsdf_at(sd, &its);
    float frac_e = (float)ne / (float)(ne + nb), frac_b = (float)nb / (float)(ne + nb);
    vec3 wi = to_local(&its.sh, vneg(ray.d));

    if (bsdf_is_smooth(b)) {
        for (uint i = 0u; i < ne; ++i) {
            EmitterQuery q;
            q.ref = its.p;
            float a = next1d(smp);
            float2 u = next2d(smp);
            vec3 le = scene_sample_emitter(sd, &q, v3(a, u.x, u.y));
            if (is_black(le) || !(q.pdf > 0.0f)) continue;
            BsdfQuery bq = bsdf_query(sd, &its, vneg(ray.d));
            bq.wi = wi;
            bq.wo = to_local(&its.sh, q.wi);
            vec3 f = bsdf_eval(b, &bq);
            if (is_black(f) || light_occluded(sd, &its, &q)) continue;
            float w = q.delta ? 1.0f : mis_power(q.pdf * frac_e, bsdf_pdf(b, &bq) * frac_b) / (float)ne;
            vec3 fle = vmul(vscale(f, fabs(bq.wo.z)), le);
            L = vadd(L, vscale(fle, w));
        }
    }

    for (uint i = 0u; i < nb; ++i) {
        BsdfQuery bq = bsdf_query(sd, &its, vneg(ray.d));
        vec3 w = bsdf_sample(b, &bq, next2d(smp));
        if (is_black(w)) continue;
        vec3 d = to_world(&its.sh, bq.wo);
        bool discrete = bq.measure == MEASURE_DISCRETE;
        Ray r = spawn_ray_from(&its, d);
        Intersection h;
        bool found = scene_intersect(sd, &r, &h);
        vec3 le = found ? hit_emission(sd, &h, d) : escaped(sd, d);
        if (is_black(le)) continue;
        float wb = 1.0f;
        if (!discrete) {
            float pe = found ? hit_emitter_pdf(sd, its.p, &h) : scene_environment_pdf(sd, d);
            wb = mis_power(bsdf_pdf(b, &bq) * frac_b, pe * frac_e);
        }
        L = vadd(L, vscale(vmul(w, le), wb / (float)nb));
    }
    return L;
}
