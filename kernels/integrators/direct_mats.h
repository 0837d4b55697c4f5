/* direct_mats: emission seen by the camera ray + one BSDF sample and the emission it finds. Delta lights
   (point, distant) cannot be found this way: scenes lit only by them come out black. */
#include "lighting.h"
INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return escaped(sd, ray.d);
    vec3 L = hit_emission(sd, &its, ray.d);
    __global const Bsdf* b = bsdf_at(sd, &its);
    BsdfQuery bq = bsdf_query(sd, &its, vneg(ray.d));
    vec3 w = bsdf_sample(b, &bq, next2d(smp));
    if (is_black(w)) return L;
    vec3 d = to_world(&its.sh, bq.wo);
    Ray r = spawn_ray_from(&its, d);
    Intersection h;
    if (!scene_intersect(sd, &r, &h)) return vadd(L, vmul(w, escaped(sd, d)));
    return vadd(L, vmul(w, hit_emission(sd, &h, d)));
}
