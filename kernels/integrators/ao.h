/* ao: ambient occlusion. One cosine-weighted direction about the shading normal: estimates
   integral V cos / pi. Escaping camera rays see 1 (an unoccluded sky). */
#include "../warp.h"
INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return v3s(1.0f);
    vec3 d = to_world(&its.sh, square_to_cosine_hemisphere(next2d(smp)));
    return scene_occluded(sd, spawn_origin(&its, d), d, 0.0f, INFINITY) ? v3s(0.0f) : v3s(1.0f);
}
