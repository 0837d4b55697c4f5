/* aov (Mitsuba 3): one geometric quantity of the camera ray's first hit (p.aov.kind, clrender/integrators/aov.py):
   0 depth (distance along the ray, in every channel), 1 position, 2 geometric normal, 3 shading normal; zero
   where the ray escapes. */
INLINE float3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return (float3)(0.0f);
    switch (sd->info->p.aov.kind) {
    case 0u: return (float3)(its.t);
    case 1u: return its.p;
    case 2u: return its.ng;
    default: return its.sh.n;
    }
}
