/* av: average visibility. One direction uniform on the hemisphere about the shading normal; 1 when nothing
   is hit within `length` (p.av.length), else 0. */
#include "../warp.h"
INLINE vec3 Li(const SceneData* sd, Ray ray, Sampler* smp) {
    Intersection its;
    if (!scene_intersect(sd, &ray, &its)) return v3s(1.0f);
    vec3 d = to_world(&its.sh, square_to_uniform_hemisphere(next2d(smp)));
    float length = sd->info->p.av.length;
    return scene_occluded(sd, spawn_origin(&its, d), d, 0.0f, length) ? v3s(0.0f) : v3s(1.0f);
}
