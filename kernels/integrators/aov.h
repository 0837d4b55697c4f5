/* aov (Mitsuba 3): one geometric quantity of the camera ray's first hit (p.aov.kind, clrender/integrators/aov.py):
   0 depth (in every channel), 1 position, 2 geometric normal, 3 shading normal; zero where the ray escapes.
   Depth is measured from the near clip plane, where Mitsuba's camera rays start (their t), not from the pinhole
   where ours do: the distance minus tmin. */
INLINE float3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return (float3)(0.0f);
    switch (sd->info->p.aov.kind) {
    case 0u: return (float3)(its.t - ray.tmin);
    case 1u: return its.p;
    case 2u: return its.ng;
    default: return its.sh.n;
    }
}
