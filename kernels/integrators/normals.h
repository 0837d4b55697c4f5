/* normals: |shading normal| per component; black where the camera ray escapes. */
INLINE float3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return (float3)(0.0f);
    return fabs(its.sh.n);
}
