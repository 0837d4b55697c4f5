/* normals: |shading normal| per component; black where the camera ray escapes. */
INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return v3s(0.0f);
    return vabs(its.sh.n);
}
