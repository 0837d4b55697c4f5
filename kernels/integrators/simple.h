/* simple (Nori): one point light given inline (p.simple.position, p.simple.energy = Φ):
   L = Φ / (4π²) · max(0, cos θ) / d² · V, i.e. a white diffuse surface lit by an isotropic point light. */
INLINE float3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return (float3)(0.0f);
    float3 pos = sd->info->p.simple.position.xyz, energy = sd->info->p.simple.energy.xyz;
    float3 v = pos - its.p;
    float d2 = dot3(v, v), d = sqrt(d2);
    float3 wi = v * (1.0f / d);
    float c = dot3(wi, its.sh.n);
    if (c <= 0.0f) return (float3)(0.0f);
    if (scene_occluded(sd, its.p, wi, ray_eps(its.p), d * (1.0f - 1e-4f))) return (float3)(0.0f);
    return energy * (c / (4.0f * M_PI_F_ * M_PI_F_ * d2));
}
