/* direct_ems: emission seen by the camera ray + one emitter sample at its hit (none at delta BSDFs). */
#include "lighting.h"
INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return escaped(sd, ray.d);
    vec3 L = hit_emission(sd, &its, ray.d);
    __global const Bsdf* b = bsdf_at(sd, &its);
    if (bsdf_is_delta(b)) return L;
    return vadd(L, sample_light(sd, &its, b, to_local(&its.sh, vneg(ray.d)), smp, false));
}
