/* direct (Nori): the exact contribution of every delta light (point, distant), each with a shadow ray:
   L = Le(camera hit) + Σ f · Φ/(4π) · cos θ / d² · V. Area and environment lights are not sampled. */
#include "lighting.h"
INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return escaped(sd, ray.d);
    vec3 L = hit_emission(sd, &its, ray.d);
    __global const Bsdf* b = bsdf_at(sd, &its);
    vec3 wi = to_local(&its.sh, vneg(ray.d));
    uint n = sd->info->n_emitters;
    for (uint e = 0u; e < n; ++e) {
        EmitterQuery q;
        q.ref = its.p;
        vec3 le = emitter_sample(sd, e, &q, (float2)(0.5f, 0.5f));
        if (!q.delta || is_black(le)) continue;
        BsdfQuery bq = bsdf_query(sd, &its, vneg(ray.d));
        bq.wi = wi;
        bq.wo = to_local(&its.sh, q.wi);
        vec3 f = bsdf_eval(b, &bq);
        if (is_black(f) || light_occluded(sd, &its, &q)) continue;
        L = vadd(L, vmul(vscale(f, fabs(bq.wo.z)), le));
    }
    return L;
}
