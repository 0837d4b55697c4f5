/* aov (Mitsuba 3): one geometric quantity of the camera ray's first hit (p.aov.kind, clrender/integrators/aov.py):
   0 depth (in every channel), 1 position, 2 geometric normal, 3 shading normal (a normalmap's or bumpmap's
   where the first hit's BSDF is one, as Mitsuba 3.9 shows it); zero where the ray escapes.
   Depth is measured from the near clip plane, where Mitsuba's camera rays start (their t), not from the pinhole
   where ours do: the distance minus tmin. */
#include "lighting.h"
INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return v3s(0.0f);
    switch (sd->info->p.aov.kind) {
    case 0u: return v3s(its.t - ray.tmin);
    case 1u: return its.p;
    case 2u: return its.ng;
    default: {
        /* the normal the BSDF shades with: a normalmap's or bumpmap's (seen from the camera), else the surface's */
        BsdfQuery q = bsdf_query(sd, &its, vneg(ray.d));
        return to_world(&its.sh, bsdf_normal(bsdf_at(sd, &its), &q));
    }
    }
}
