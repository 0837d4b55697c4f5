/* material: the BSDF value at the first hit for wi = back along the ray, wo = the shading normal (ETH Nori's pa1
   integrator; clrender/integrators/material.py). No lights are sampled: it shows BSDFs and textures as they are. */
#include "lighting.h"
INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return v3s(0.0f);
    BsdfQuery bq = bsdf_query(sd, &its, vneg(ray.d));
    bq.wo = v3(0.0f, 0.0f, 1.0f);
    return bsdf_eval(bsdf_at(sd, &its), &bq);
}
