/* simple (Nori): one point light given inline (p.simple.position, p.simple.energy = Φ):
   L = Φ / (4π²) · max(0, cos θ) / d² · V, i.e. a white diffuse surface lit by an isotropic point light. */
INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return v3s(0.0f);
    vec3 pos = vrow(sd->info->p.simple.position), energy = vrow(sd->info->p.simple.energy);
    vec3 v = vsub(pos, its.p);
    float d2 = dot3(v, v), d = sqrt(d2);
    vec3 wi = vscale(v, 1.0f / d);
    float c = dot3(wi, its.sh.n);
    if (c <= 0.0f) return v3s(0.0f);
    if (scene_occluded(sd, spawn_origin(&its, wi), wi, 0.0f, d * (1.0f - 1e-4f))) return v3s(0.0f);
    return vscale(energy, c / (4.0f * M_PI_F_ * M_PI_F_ * d2));
}
