/* whitted (Nori): at diffuse/glossy hits, emission + one emitter sample; at mirror/dielectric hits,
   continue along the sampled direction with probability 0.95 (dividing by it) — a loop, not recursion. */
#include "lighting.h"
INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    vec3 L = v3s(0.0f), beta = v3s(1.0f);
    for (uint depth = 0u; depth < 100000u; ++depth) {
        Intersection its;
        if (!scene_intersect(sd, &ray, &its)) return vadd(L, vmul(beta, escaped(sd, ray.d)));
        L = vadd(L, vmul(beta, hit_emission(sd, &its, ray.d)));
        __global const Bsdf* b = bsdf_at(sd, &its);
        if (!bsdf_is_delta(b))
            return vadd(L, vmul(beta, sample_light(sd, &its, b, to_local(&its.sh, vneg(ray.d)), smp, false)));
        if (!(next1d(smp) < 0.95f)) return L;
        BsdfQuery bq = bsdf_query(sd, &its, vneg(ray.d));
        vec3 w = bsdf_sample(b, &bq, next2d(smp));
        if (is_black(w)) return L;
        beta = vmul(beta, vscale(w, 1.0f / 0.95f));
        ray = spawn_ray_from(&its, to_world(&its.sh, bq.wo));
    }
    return L;
}
