/* direct_mis: one emitter sample and one BSDF sample, combined with the balance heuristic. At delta BSDFs
   only the BSDF sample counts, with full weight. */
#include "lighting.h"
INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return escaped(sd, ray.d);
    vec3 L = hit_emission(sd, &its, ray.d);
    __global const Bsdf* b = bsdf_at(sd, &its);
    bool delta = bsdf_is_delta(b);
    vec3 wi = to_local(&its.sh, vneg(ray.d));
    if (!delta) L = vadd(L, sample_light(sd, &its, b, wi, smp, true));
    BsdfQuery bq = bsdf_query(sd, &its, vneg(ray.d));
    vec3 w = bsdf_sample(b, &bq, next2d(smp));
    if (is_black(w)) return L;
    vec3 d = to_world(&its.sh, bq.wo);
    bool discrete = bq.measure == MEASURE_DISCRETE;
    float pb = discrete ? 0.0f : bsdf_pdf(b, &bq);
    Ray r = spawn_ray_from(&its, d);
    Intersection h;
    if (!scene_intersect(sd, &r, &h)) {
        vec3 le = escaped(sd, d);
        if (is_black(le)) return L;
        float wb = discrete ? 1.0f : mis_balance(pb, scene_environment_pdf(sd, d));
        return vadd(L, vscale(vmul(w, le), wb));
    }
    vec3 le = hit_emission(sd, &h, d);
    if (is_black(le)) return L;
    float wb = discrete ? 1.0f : mis_balance(pb, hit_emitter_pdf(sd, its.p, &h));
    return vadd(L, vscale(vmul(w, le), wb));
}
